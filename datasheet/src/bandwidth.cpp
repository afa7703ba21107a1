// Gain and phase of the gyros against the table encoder from oscillate steps; the -3 dB
// bandwidth and the pure delay of the output.
#include "datasheet/bandwidth.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

#include "bandwidth_curve.hpp"
#include "core/error.hpp"
#include "core/rotation.hpp"
#include "solver/run_setup.hpp"
#include "store/run_store.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr std::size_t kMinEncoderRows = 8;
/// Segments a point's uncertainty is read from: at most 10 (2 periods each in a 20-period
/// record), at least 4 (fewer, and the sigma itself would be a guess: no interval then).
constexpr int kMaxSegments = 10;
constexpr int kMinSegments = 4;
/// Bootstrap draws of the intervals: the 2.5 % tail then rests on 100 draws.
constexpr int kBootstrapDraws = 4000;
constexpr double kConfidence = 0.95;

// The sine at angular frequency w through (t, y) by least squares, with an offset (bias, Earth
// rate) in the model: y = a sin(w t) + b cos(w t) + c. Returned as the phasor a + i b, so that
// y = |p| sin(w t + arg p).
std::complex<double> fit_sine(const std::vector<double>& t, const std::vector<double>& y,
                              double w) {
  Eigen::MatrixXd a(static_cast<Eigen::Index>(t.size()), 3);
  Eigen::VectorXd b(static_cast<Eigen::Index>(t.size()));
  for (std::size_t i = 0; i < t.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    a(r, 0) = std::sin(w * t[i]);
    a(r, 1) = std::cos(w * t[i]);
    a(r, 2) = 1.0;
    b(r) = y[i];
  }
  const Eigen::Vector3d x = a.colPivHouseholderQr().solve(b);
  return {x(0), x(1)};
}

// The uncertainty of one point from the scatter of its parts: the record cut into segments of
// whole periods, the gyro and encoder sines fitted in each, and the spread of the segments'
// gain and phase about the whole record's, divided by sqrt(segments) (batch means). The
// residuals of one fit would not do: the IMU's output filter correlates its noise over many
// samples, and the least-squares covariance, which takes them as independent, would be several
// times too small; segments of whole periods are long against that correlation, and they
// carry the encoder's noise and the table's motion as they are.
struct PointSigma {
  double gain = 0.0;       ///< [ratio]
  double phase_rad = 0.0;  ///< [rad]
  int segments = 0;
};

PointSigma segment_sigma(const std::vector<double>& gyro_t, const std::vector<double>& gyro_y,
                         const std::vector<double>& table_t, const std::vector<double>& table_y,
                         double w, double f, std::complex<double> whole) {
  PointSigma out;
  // The record spans its periods less one sample period (first to last sample): count a period
  // that lacks less than a tenth of itself.
  const double span = std::min(gyro_t.back(), table_t.back());
  const auto periods = static_cast<int>(std::floor(span * f + 0.1));
  const int segments = std::min(periods, kMaxSegments);
  if (segments < kMinSegments) return out;
  const auto slice = [](const std::vector<double>& t, const std::vector<double>& y, double a,
                        double b, std::vector<double>& ts, std::vector<double>& ys) {
    ts.clear();
    ys.clear();
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (t[i] >= a && t[i] < b) ts.push_back(t[i]), ys.push_back(y[i]);
    }
  };
  // Whole periods each, as even as they divide (the record's every sample in one segment);
  // a segment of n periods weighs n: its variance goes as 1/n.
  std::vector<double> gains, phases, weights, ts, ys;
  int start = 0;
  for (int k = 0; k < segments; ++k) {
    const int end =
        static_cast<int>(std::lround(static_cast<double>((k + 1) * periods) / segments));
    const double a = start / f;
    const double b = k + 1 == segments ? INFINITY : end / f;
    slice(gyro_t, gyro_y, a, b, ts, ys);
    if (ts.size() < kMinEncoderRows) return out;
    const std::complex<double> gyro = fit_sine(ts, ys, w);
    slice(table_t, table_y, a, b, ts, ys);
    if (ts.size() < kMinEncoderRows) return out;
    const std::complex<double> table = fit_sine(ts, ys, w);
    const std::complex<double> ratio = gyro / table;
    gains.push_back(std::abs(ratio));
    phases.push_back(std::arg(ratio / whole));  // about the whole record's: no wrap
    weights.push_back(end - start);
    start = end;
  }
  // Standard error of the weighted mean: sum w (x - mean)^2 / (K - 1) / sum w.
  const auto standard_error = [&](const std::vector<double>& v) {
    double sw = 0.0, mean = 0.0;
    for (std::size_t k = 0; k < v.size(); ++k) sw += weights[k], mean += weights[k] * v[k];
    mean /= sw;
    double ss = 0.0;
    for (std::size_t k = 0; k < v.size(); ++k) ss += weights[k] * (v[k] - mean) * (v[k] - mean);
    return std::sqrt(ss / static_cast<double>(v.size() - 1) / sw);
  };
  out.gain = standard_error(gains);
  out.phase_rad = standard_error(phases);
  out.segments = segments;
  return out;
}

// Mean of wrapping angles [deg].
double circular_mean_deg(const std::vector<core::TableState>& rows, bool inner) {
  double s = 0.0, c = 0.0;
  for (const auto& r : rows) {
    const double a = (inner ? r.inner.angle_deg : r.outer.angle_deg) * kPi / 180.0;
    s += std::sin(a);
    c += std::cos(a);
  }
  return std::atan2(s, c) * 180.0 / kPi;
}

}  // namespace

BandwidthAnalysis analyse_bandwidth(store::Database& db, std::int64_t run,
                                    const std::string& device) {
  BandwidthAnalysis out;
  out.run = run;
  out.confidence = kConfidence;
  out.device = store::choose_device(db, run, device);
  store::RunStore runs(db);
  const solver::RunSetup setup = solver::run_setup(runs.load_run(run), run, out.device);

  store::for_each_step_data(db, run, out.device, [&](const store::StepData& data) {
    if (data.step.kind != "oscillate" || data.samples.size() < kMinEncoderRows) return;
    const double f = data.step.commanded.value("frequency_hz", 0.0);
    const std::string table_axis = data.step.commanded.value("axis", "");
    const bool inner = table_axis == "inner";
    if (!(f > 0.0) || (!inner && table_axis != "outer")) return;
    const double t0 = data.samples.front().receive_time_s;
    const double t1 = data.samples.back().receive_time_s;
    const auto rows = runs.table_telemetry(run, t0, t1);
    if (rows.size() < kMinEncoderRows) {
      throw core::InputError(
          fmt::format("run {}", run),
          fmt::format("step {} ({}) has {} encoder readings in its record, too few to fit a sine "
                      "(at least {}): was it recorded by a calstand that traces oscillations?",
                      data.step.index, data.step.label, rows.size(), kMinEncoderRows));
    }
    // The oscillating axis in the body frame, at the step's mean angles (the other axis holds,
    // the oscillating one swings by a small amplitude about its mean).
    const double outer_deg = circular_mean_deg(rows, false);
    const double inner_deg = circular_mean_deg(rows, true);
    const Eigen::Vector3d axis_level =
        setup.geometry.table_rate_level_dps(outer_deg, inner ? 0.0 : 1.0, inner ? 1.0 : 0.0);
    const Eigen::Vector3d axis_body =
        setup.geometry.body_to_level(outer_deg, inner_deg).transpose() * axis_level;
    int body = 0;
    axis_body.cwiseAbs().maxCoeff(&body);

    // Times from the record's start: the phasors of both fits share one time origin.
    const double w = 2.0 * kPi * f;
    std::vector<double> t, y;
    for (const auto& s : data.samples) {
      t.push_back(s.receive_time_s - t0);
      y.push_back(s.gyro_dps[body]);
    }
    const std::complex<double> gyro = fit_sine(t, y, w);
    const std::vector<double> gyro_t = std::move(t), gyro_y = std::move(y);
    t.clear();
    y.clear();
    for (const auto& r : rows) {
      t.push_back(r.time_s - t0);
      // The rate seen along the body axis: the encoder rate times the axis's projection on it.
      y.push_back((inner ? r.inner.rate_dps : r.outer.rate_dps) * axis_body[body]);
    }
    const std::complex<double> table = fit_sine(t, y, w);
    const PointSigma sigma = segment_sigma(gyro_t, gyro_y, t, y, w, f, gyro / table);

    BandwidthPoint p;
    p.step = data.step.index;
    p.label = data.step.label;
    p.axis = body;
    p.frequency_hz = f;
    p.gain = std::abs(gyro) / std::abs(table);
    p.gain_db = 20.0 * std::log10(p.gain);
    p.phase_deg = std::arg(gyro / table) * 180.0 / kPi;
    p.table_amplitude_dps = std::abs(table);
    p.gain_sigma = sigma.gain;
    p.phase_sigma_deg = sigma.phase_rad * 180.0 / kPi;
    p.segments = sigma.segments;
    p.samples = data.samples.size();
    p.encoder_rows = rows.size();
    out.points.push_back(std::move(p));
  });
  if (out.points.empty()) {
    throw core::InputError(fmt::format("run {}", run),
                           fmt::format("has no completed oscillate step of {}: nothing for a "
                                       "bandwidth analysis (run the library procedure bandwidth)",
                                       out.device));
  }
  std::stable_sort(out.points.begin(), out.points.end(),
                   [](const BandwidthPoint& a, const BandwidthPoint& b) {
                     return a.axis != b.axis ? a.axis < b.axis : a.frequency_hz < b.frequency_hz;
                   });

  for (int axis = 0; axis < 3; ++axis) {
    std::vector<BandwidthPoint*> curve;
    for (auto& p : out.points) {
      if (p.axis == axis) curve.push_back(&p);
    }
    if (curve.empty()) continue;
    // A lag grows with frequency past -180 deg: unwrap so that neighbours differ by less than
    // half a turn, starting from the lowest frequency (where the lag is small).
    for (std::size_t k = 1; k < curve.size(); ++k) {
      double d = curve[k]->phase_deg - curve[k - 1]->phase_deg;
      while (d > 180.0) d -= 360.0, curve[k]->phase_deg -= 360.0;
      while (d < -180.0) d += 360.0, curve[k]->phase_deg += 360.0;
    }
    std::vector<detail::CurvePoint> points;
    for (const BandwidthPoint* p : curve) {
      detail::CurvePoint c;
      c.frequency_hz = p->frequency_hz;
      c.gain = p->gain;
      c.phase_rad = p->phase_deg * kPi / 180.0;
      c.gain_sigma = p->gain_sigma;
      c.phase_sigma_rad = p->phase_sigma_deg * kPi / 180.0;
      c.sigma_dof = p->segments - 1.0;
      points.push_back(c);
    }
    const auto a = static_cast<std::size_t>(axis);
    const detail::CurveFigures figures = detail::read_curve(points);
    out.bandwidth_hz[a] = figures.bandwidth_hz;
    out.low_pass_order[a] = figures.low_pass_order;
    out.delay_s[a] = figures.delay_s;
    // Seeded by run and axis: the same run always gives the same intervals.
    const detail::CurveIntervals intervals = detail::bootstrap_curve(
        points, out.confidence, kBootstrapDraws, static_cast<std::uint64_t>(run) * 3U + a);
    if (intervals.bandwidth_hz) {
      out.bandwidth_interval_hz[a] = {intervals.bandwidth_hz->lo, intervals.bandwidth_hz->hi};
      out.bandwidth_sigma_hz[a] = intervals.bandwidth_hz->sigma;
    }
    if (intervals.delay_s) {
      out.delay_interval_s[a] = {intervals.delay_s->lo, intervals.delay_s->hi};
      out.delay_sigma_s[a] = intervals.delay_s->sigma;
    }
  }
  return out;
}

nlohmann::json to_json(const BandwidthAnalysis& b) {
  const auto triple = [](const std::array<std::optional<double>, 3>& v) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& x : v) j.push_back(x ? nlohmann::json(*x) : nlohmann::json(nullptr));
    return j;
  };
  const auto intervals = [](const std::array<std::optional<std::array<double, 2>>, 3>& v) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& x : v) j.push_back(x ? nlohmann::json(*x) : nlohmann::json(nullptr));
    return j;
  };
  nlohmann::json points = nlohmann::json::array();
  for (const auto& p : b.points) {
    points.push_back({{"axis", std::string(1, static_cast<char>('x' + p.axis))},
                      {"frequency_hz", p.frequency_hz},
                      {"gain", p.gain},
                      {"gain_db", p.gain_db},
                      {"phase_deg", p.phase_deg},
                      {"gain_sigma", p.gain_sigma},
                      {"phase_sigma_deg", p.phase_sigma_deg},
                      {"segments", p.segments},
                      {"step", p.step},
                      {"label", p.label}});
  }
  return {{"run", b.run},
          {"device", b.device},
          {"gyro",
           {{"bandwidth_hz", triple(b.bandwidth_hz)},
            {"delay_s", triple(b.delay_s)},
            {"low_pass_order", b.low_pass_order},
            {"confidence", b.confidence},
            {"bandwidth_interval_hz", intervals(b.bandwidth_interval_hz)},
            {"bandwidth_sigma_hz", triple(b.bandwidth_sigma_hz)},
            {"delay_interval_s", intervals(b.delay_interval_s)},
            {"delay_sigma_s", triple(b.delay_sigma_s)},
            {"points", std::move(points)}}}};
}

}  // namespace calstand::analysis

// Gain and phase of the gyros against the table encoder from oscillate steps; the -3 dB
// bandwidth and the pure delay of the output.
#include "analysis/bandwidth.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "solver/run_setup.hpp"
#include "store/run_store.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kHalfPowerDb = -3.0102999566398120;  // 10 log10(1/2)
constexpr std::size_t kMinEncoderRows = 8;
constexpr std::array kLowPassOrders{1, 2, 4, 6, 8};

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

// Phase [rad] of an analogue Butterworth low-pass of `order` at f / fc = x: its poles lie on the
// unit circle of the left half plane, and the phase is minus the sum of their angles seen from
// i x. Order 1 is the first-order lag, -atan(x).
double butterworth_phase(int order, double x) {
  double phase = 0.0;
  for (int k = 1; k <= order; ++k) {
    const std::complex<double> pole =
        std::polar(1.0, kPi * (2.0 * k + order - 1.0) / (2.0 * order));
    phase -= std::arg(std::complex<double>(0.0, x) - pole);
  }
  return phase;
}

double butterworth_gain_db(int order, double x) {
  return -10.0 * std::log10(1.0 + std::pow(x, 2.0 * order));
}

// The -3 dB crossing of one axis's gain curve, interpolated linearly in dB over log frequency
// between the first two neighbours that straddle it.
std::optional<double> half_power(const std::vector<const BandwidthPoint*>& curve) {
  for (std::size_t k = 1; k < curve.size(); ++k) {
    const double g0 = curve[k - 1]->gain_db, g1 = curve[k]->gain_db;
    if (g0 >= kHalfPowerDb && g1 < kHalfPowerDb) {
      const double l0 = std::log(curve[k - 1]->frequency_hz), l1 = std::log(curve[k]->frequency_hz);
      return std::exp(l0 + (kHalfPowerDb - g0) / (g1 - g0) * (l1 - l0));
    }
  }
  return std::nullopt;
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
    t.clear();
    y.clear();
    for (const auto& r : rows) {
      t.push_back(r.time_s - t0);
      // The rate seen along the body axis: the encoder rate times the axis's projection on it.
      y.push_back((inner ? r.inner.rate_dps : r.outer.rate_dps) * axis_body[body]);
    }
    const std::complex<double> table = fit_sine(t, y, w);

    BandwidthPoint p;
    p.step = data.step.index;
    p.label = data.step.label;
    p.axis = body;
    p.frequency_hz = f;
    p.gain = std::abs(gyro) / std::abs(table);
    p.gain_db = 20.0 * std::log10(p.gain);
    p.phase_deg = std::arg(gyro / table) * 180.0 / kPi;
    p.table_amplitude_dps = std::abs(table);
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
    const std::vector<const BandwidthPoint*> points(curve.begin(), curve.end());
    const auto fc = half_power(points);
    out.bandwidth_hz[static_cast<std::size_t>(axis)] = fc;
    int order = 0;
    if (fc) {
      double best = std::numeric_limits<double>::infinity();
      for (const int n : kLowPassOrders) {
        double cost = 0.0;
        for (const auto* p : points) {
          const double r = p->gain_db - butterworth_gain_db(n, p->frequency_hz / *fc);
          cost += r * r;
        }
        if (cost < best) best = cost, order = n;
      }
    }
    out.low_pass_order[static_cast<std::size_t>(axis)] = order;
    if (points.size() < 2) continue;
    // What the low-pass model does not explain of the phase is the delay: -w tau.
    double num = 0.0, den = 0.0;
    for (const auto* p : points) {
      const double omega = 2.0 * kPi * p->frequency_hz;
      const double model = order > 0 ? butterworth_phase(order, p->frequency_hz / *fc) : 0.0;
      num += (p->phase_deg * kPi / 180.0 - model) * omega;
      den += omega * omega;
    }
    out.delay_s[static_cast<std::size_t>(axis)] = -num / den;
  }
  return out;
}

nlohmann::json to_json(const BandwidthAnalysis& b) {
  const auto triple = [](const std::array<std::optional<double>, 3>& v) {
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
                      {"step", p.step},
                      {"label", p.label}});
  }
  return {{"run", b.run},
          {"device", b.device},
          {"gyro",
           {{"bandwidth_hz", triple(b.bandwidth_hz)},
            {"delay_s", triple(b.delay_s)},
            {"low_pass_order", b.low_pass_order},
            {"points", std::move(points)}}}};
}

}  // namespace calstand::analysis

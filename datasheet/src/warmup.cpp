#include "datasheet/warmup.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "core/error.hpp"
#include "datasheet_units.hpp"
#include "store/run_store.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {
namespace {

constexpr double kMinDurationS = 60.0;
/// Bins over the record: fine enough for a transient of a few bins, coarse enough that each
/// bin's mean averages the white noise down.
constexpr double kBinsPerRecord = 400.0;
/// A temperature change below this over the capture is not worth a term [degC].
constexpr double kMinTemperatureRiseC = 0.05;
/// Level of the F-test that lets the temperature term in (see fit_channel()).
constexpr double kTemperatureTermP = 1e-6;

struct Binned {
  std::vector<double> t_s;
  std::vector<double> temperature_c;
  std::array<std::vector<double>, 6> y;
};

Binned bin_samples(const std::vector<core::ImuSample>& samples, double bin_s) {
  Binned b;
  const double t0 = samples.front().receive_time_s;
  std::size_t i = 0;
  while (i < samples.size()) {
    const double start = t0 + static_cast<double>(b.t_s.size()) * bin_s;
    double t = 0.0, temp = 0.0;
    std::array<double, 6> sum{};
    std::size_t n = 0;
    for (; i < samples.size() && samples[i].receive_time_s < start + bin_s; ++i, ++n) {
      t += samples[i].receive_time_s - t0;
      temp += samples[i].temperature_c;
      for (int c = 0; c < 3; ++c) {
        sum[c] += samples[i].gyro_dps[c];
        sum[c + 3] += samples[i].accel_mps2[c];
      }
    }
    if (n == 0) {  // a gap: the bin is skipped
      b.t_s.push_back(std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    const auto count = static_cast<double>(n);
    b.t_s.push_back(t / count);
    b.temperature_c.push_back(temp / count);
    for (int c = 0; c < 6; ++c) b.y[c].push_back(sum[c] / count);
  }
  // Drop the NaN placeholders of empty bins (they only kept the bin grid).
  b.t_s.erase(std::remove_if(b.t_s.begin(), b.t_s.end(), [](double v) { return std::isnan(v); }),
              b.t_s.end());
  return b;
}

struct LinearFit {
  Eigen::VectorXd coef;
  Eigen::MatrixXd covariance;
  double sse = std::numeric_limits<double>::infinity();
};

// y = c + A exp(-t / tau) [+ k (T - T_end)] at fixed tau, by least squares.
LinearFit fit_at(const Binned& b, const std::vector<double>& y, double tau_s,
                 bool with_temperature) {
  const auto n = static_cast<Eigen::Index>(y.size());
  Eigen::MatrixXd x(n, with_temperature ? 3 : 2);
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    x(i, 0) = 1.0;
    x(i, 1) = std::exp(-b.t_s[i] / tau_s);
    if (with_temperature) x(i, 2) = b.temperature_c[i] - b.temperature_c.back();
    v(i) = y[i];
  }
  LinearFit f;
  const Eigen::MatrixXd xtx = x.transpose() * x;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(xtx);
  if (ldlt.info() != Eigen::Success) return f;
  f.coef = ldlt.solve(x.transpose() * v);
  const Eigen::VectorXd r = v - x * f.coef;
  f.sse = r.squaredNorm();
  const double s2 = f.sse / static_cast<double>(std::max<Eigen::Index>(1, n - x.cols()));
  f.covariance = s2 * ldlt.solve(Eigen::MatrixXd::Identity(x.cols(), x.cols()));
  return f;
}

struct TauFit {
  double tau_s = 0.0;
  LinearFit fit;
};

TauFit best_tau(const Binned& b, const std::vector<double>& y, double bin_s, double duration_s,
                bool with_temperature);

ChannelWarmup fit_channel(const Binned& b, const std::vector<double>& y, double k, double band,
                          double bin_s, double duration_s, bool temperature_varies,
                          bool& temperature_used) {
  TauFit chosen = best_tau(b, y, bin_s, duration_s, false);
  temperature_used = false;
  if (temperature_varies) {
    // The unit's temperature enters only when it explains far more than noise would: its
    // warming follows an exponential too, and a term it does not need takes the transient's
    // place. The bins' residuals are correlated (in-run bias wander), so the F-test's nominal
    // level overstates the evidence; hence a very small one.
    const TauFit with_t = best_tau(b, y, bin_s, duration_s, true);
    const double dof = static_cast<double>(y.size()) - 4.0;
    const double f = (chosen.fit.sse - with_t.fit.sse) / (with_t.fit.sse / dof);
    if (dof > 0 && f > boost::math::quantile(boost::math::complement(
                           boost::math::fisher_f(1.0, dof), kTemperatureTermP))) {
      chosen = with_t;
      temperature_used = true;
    }
  }
  const double tau = chosen.tau_s;
  const LinearFit& f = chosen.fit;
  ChannelWarmup out;
  out.settled = k * f.coef(0);
  out.amplitude = k * f.coef(1);
  out.amplitude_sigma = k * std::sqrt(f.covariance(1, 1));
  out.time_constant_s = tau;
  out.time_to_band_s =
      std::abs(out.amplitude) > band ? tau * std::log(std::abs(out.amplitude) / band) : 0.0;
  out.resolved = std::abs(out.amplitude) > 3.0 * out.amplitude_sigma && tau > 2.0 * bin_s &&
                 tau < duration_s / 3.0;
  out.temperature_term = temperature_used;
  return out;
}

TauFit best_tau(const Binned& b, const std::vector<double>& y, double bin_s, double duration_s,
                bool with_temperature) {
  // tau on a log grid from two bins to half the record, then golden section around the best.
  const double lo = std::log(2.0 * bin_s);
  const double hi = std::log(0.5 * duration_s);
  constexpr int kGrid = 120;
  int best = 0;
  double best_sse = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kGrid; ++i) {
    const double sse = fit_at(b, y, std::exp(lo + (hi - lo) * i / kGrid), with_temperature).sse;
    if (sse < best_sse) {
      best_sse = sse;
      best = i;
    }
  }
  double a = lo + (hi - lo) * std::max(0, best - 1) / kGrid;
  double c = lo + (hi - lo) * std::min(kGrid, best + 1) / kGrid;
  const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int it = 0; it < 60; ++it) {
    const double x1 = c - golden * (c - a);
    const double x2 = a + golden * (c - a);
    if (fit_at(b, y, std::exp(x1), with_temperature).sse <
        fit_at(b, y, std::exp(x2), with_temperature).sse) {
      c = x2;
    } else {
      a = x1;
    }
  }
  const double tau = std::exp(0.5 * (a + c));
  return {tau, fit_at(b, y, tau, with_temperature)};
}

// The capture to analyse: the one asked for, or the first completed one after a power-on step
// (the step records: power steps hold no samples).
std::size_t warmup_capture(const std::vector<store::StepRecord>& steps,
                           std::optional<std::size_t> step, std::int64_t run) {
  if (step) return *step;
  bool powered_on = false;
  for (const auto& s : steps) {
    if (s.kind == "power") {
      powered_on = s.commanded.value("power", "") == "on";
      continue;
    }
    if (powered_on && s.kind == "capture" && s.status == store::StepStatus::kCompleted) {
      return s.index;
    }
  }
  throw core::InputError(fmt::format("run {}", run),
                         "has no capture after a power-on step (library procedure warm-up); "
                         "give --step");
}

}  // namespace

WarmupAnalysis analyse_warmup(store::Database& db, std::int64_t run, const std::string& device,
                              std::optional<std::size_t> step, double band_deg_per_h,
                              double band_ug) {
  WarmupAnalysis out;
  out.run = run;
  out.device = store::choose_device(db, run, device);
  const std::size_t index = warmup_capture(store::RunStore(db).load_steps(run), step, run);
  std::optional<store::StepData> capture;
  for (store::StepData& s : store::read_step_data(db, run, out.device)) {
    if (s.step.index == index && s.step.kind == "capture") capture = std::move(s);
  }
  if (!capture) {
    throw core::InputError(fmt::format("run {} step {}", run, index),
                           "is not a completed capture with samples");
  }
  out.step = capture->step.index;
  out.step_label = capture->step.label;
  const auto& samples = capture->samples;
  out.duration_s =
      samples.empty() ? 0.0 : samples.back().receive_time_s - samples.front().receive_time_s;
  if (out.duration_s < kMinDurationS) {
    throw core::InputError(fmt::format("run {} step {}", run, out.step),
                           fmt::format("records {:.0f} s; a warm-up fit needs at least {:.0f} s",
                                       out.duration_s, kMinDurationS));
  }
  out.bin_s = out.duration_s / kBinsPerRecord;
  out.band_deg_per_h = band_deg_per_h;
  out.band_ug = band_ug;
  const Binned b = bin_samples(samples, out.bin_s);
  const auto [tmin, tmax] = std::minmax_element(b.temperature_c.begin(), b.temperature_c.end());
  out.temperature_rise_c = *tmax - *tmin;
  out.with_temperature = out.temperature_rise_c > kMinTemperatureRiseC;  // a candidate term
  static constexpr std::array<const char*, 6> kNames = {"gx", "gy", "gz", "ax", "ay", "az"};
  for (std::size_t c = 0; c < 6; ++c) {
    const bool gyro = c < 3;
    bool used = false;
    out.channels[c] = fit_channel(b, b.y[c], gyro ? kDegPerSToDegPerH : kMps2ToUg,
                                  gyro ? band_deg_per_h : band_ug, out.bin_s, out.duration_s,
                                  out.with_temperature, used);
    out.channels[c].channel = kNames[c];
  }
  return out;
}

nlohmann::json to_json(const WarmupAnalysis& w) {
  const auto sensor = [&](std::size_t first, const char* unit) {
    nlohmann::json amp = nlohmann::json::array(), sig = nlohmann::json::array(),
                   tau = nlohmann::json::array(), band = nlohmann::json::array(),
                   resolved = nlohmann::json::array(), temperature = nlohmann::json::array();
    for (std::size_t c = first; c < first + 3; ++c) {
      const ChannelWarmup& ch = w.channels[c];
      amp.push_back(ch.amplitude);
      sig.push_back(ch.amplitude_sigma);
      tau.push_back(ch.time_constant_s);
      band.push_back(ch.time_to_band_s);
      resolved.push_back(ch.resolved);
      temperature.push_back(ch.temperature_term);
    }
    return nlohmann::json{{fmt::format("amplitude_{}", unit), amp},
                          {fmt::format("amplitude_sigma_{}", unit), sig},
                          {"time_constant_s", tau},
                          {"time_to_band_s", band},
                          {"resolved", resolved},
                          {"temperature_term", temperature}};
  };
  return {{"run", w.run},
          {"device", w.device},
          {"step", w.step},
          {"step_label", w.step_label},
          {"duration_s", w.duration_s},
          {"bin_s", w.bin_s},
          {"temperature_rise_c", w.temperature_rise_c},
          {"with_temperature", w.with_temperature},
          {"band", {{"deg_per_h", w.band_deg_per_h}, {"ug", w.band_ug}}},
          {"gyro", sensor(0, "deg_per_h")},
          {"accel", sensor(3, "ug")}};
}

}  // namespace calstand::analysis

#pragma once
// The warm-up campaigns of issue 28, shared by its test
// (tests/unit/solver/effect_or_wander_test.cpp) and its detection sweep
// (bench/warm_up_detection_bench.cpp): a default thermal calibration at 25, -10 and 60 degC with a
// gyro bias that settles after power-on, on white, LN200-, ADIS16488- and MEMS-class noise.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/noise.hpp"
#include "sim/spec_sheet.hpp"
#include "sim_run.hpp"

namespace calstand::solver::testing {

inline constexpr double kStaticStepS = 60.0;
inline constexpr double kRateHz = 50.0;

/// The campaign as the library's thermal-calibration records it by default, at 25, -10
/// and 60 degC (time and temperature not confounded): each plateau a soak (unrecorded; none
/// before the first, which starts at power-on), a 60 s capture at every outer x inner angle
/// (8 x 3) and turns about every body axis at four rates both ways, two revolutions each;
/// optionally a static capture of `static_capture_s` at the start.
inline std::vector<SimStep> warm_up_campaign(double static_capture_s) {
  std::vector<SimStep> steps;
  if (static_capture_s > 0.0) {
    SimStep s;
    s.temperature_c = 25.0;
    s.duration_s = static_capture_s;
    steps.push_back(s);
  }
  for (double temp : {25.0, -10.0, 60.0}) {
    bool first = true;
    for (double outer = 0.0; outer < 360.0; outer += 45.0) {
      for (double inner : {0.0, 45.0, 90.0}) {
        SimStep s;
        s.outer_deg = outer;
        s.inner_deg = inner;
        s.temperature_c = temp;
        s.duration_s = kStaticStepS;
        s.gap_before_s = first ? (temp == 25.0 ? 8.0 : 1800.0) : 10.0;
        first = false;
        steps.push_back(s);
      }
    }
    for (double rate : {10.0, 30.0, 100.0, 300.0}) {
      for (auto s : rate_steps({rate}, temp, 720.0 / rate)) {
        s.gap_before_s = 4.0;
        steps.push_back(s);
      }
    }
  }
  return steps;
}

inline sim::ImuTruth white_noise_unit(std::uint64_t seed) {
  sim::ImuTruth t = white_noise_truth(2e-3, 5e-4, kRateHz);
  sim::NormalSource n(seed);
  draw_classical_errors(t, n);
  return t;
}

inline sim::ImuTruth unit_of(const std::string& noise, std::uint64_t seed) {
  if (noise == "white") return white_noise_unit(seed);
  if (noise == "mems") {
    sim::ImuTruth t = mems_gauss_markov_unit(seed);
    t.sample_rate_hz = kRateHz;
    return t;
  }
  return datasheet_unit(noise.c_str(), seed, kRateHz);
}

/// A static step mean's noise on the unit's gyros as a station sees it: the standard deviation
/// of the means of consecutive 30 s windows of three hours at rest (white noise and wander),
/// the largest of the three axes.
inline double step_mean_noise_dps(const sim::ImuTruth& truth, std::uint64_t seed) {
  SimStep rest;
  rest.duration_s = 3.0 * 3600.0;
  const RunData data = simulate_run(truth, {rest}, seed);
  const auto& samples = data.steps.front().samples;
  const auto per_window = static_cast<std::size_t>(kStaticStepS * truth.sample_rate_hz);
  double largest = 0.0;
  for (int a = 0; a < 3; ++a) {
    std::vector<double> means;
    for (std::size_t i = 0; i + per_window <= samples.size(); i += per_window) {
      double sum = 0.0;
      for (std::size_t k = i; k < i + per_window; ++k) sum += samples[k].gyro_dps[a];
      means.push_back(sum / static_cast<double>(per_window));
    }
    double mean = 0.0;
    for (double m : means) mean += m;
    mean /= static_cast<double>(means.size());
    double var = 0.0;
    for (double m : means) var += (m - mean) * (m - mean);
    largest = std::max(largest, std::sqrt(var / static_cast<double>(means.size() - 1)));
  }
  return largest;
}

/// `truth` on the campaign with a gyro warm-up from power-on (t = 0, the first sample) on every
/// axis (1, -0.6, 0.8 times `amplitude_dps`) with one time constant.
inline RunData warm_up_run(const sim::ImuTruth& truth, double static_capture_s, double tau_s,
                           double amplitude_dps, std::uint64_t seed) {
  RunData data = simulate_run(truth, warm_up_campaign(static_capture_s), seed);
  const Eigen::Vector3d warm = amplitude_dps * Eigen::Vector3d(1.0, -0.6, 0.8);
  for (auto& step : data.steps) {
    for (auto& s : step.samples) s.gyro_dps += warm * std::exp(-s.receive_time_s / tau_s);
  }
  return data;
}

}  // namespace calstand::solver::testing

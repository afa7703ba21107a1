#include "tablefree/static_detector.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>

#include "core/error.hpp"

namespace calstand::solver {

namespace {

constexpr const char* kDetectorWhere = "static detector";

const char* detector_rule_name(ThresholdRule r) {
  switch (r) {
    case ThresholdRule::kRestQuantile:
      return "rest_quantile";
    case ThresholdRule::kMultiple:
      return "multiple";
    case ThresholdRule::kAbsolute:
      return "absolute";
  }
  return "rest_quantile";
}

double detector_median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

void detector_check(const StaticDetectorOptions& o) {
  const auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  if (!positive(o.window_s)) throw core::InputError(kDetectorWhere, "window_s must be positive");
  if (!(std::isfinite(o.min_duration_s) && o.min_duration_s >= 0.0)) {
    throw core::InputError(kDetectorWhere, "min_duration_s must be >= 0");
  }
  if (!(std::isfinite(o.initial_rest_s) && o.initial_rest_s >= 0.0)) {
    throw core::InputError(kDetectorWhere, "initial_rest_s must be >= 0 (0: found from the data)");
  }
  if (!positive(o.rest_probe_s) || !positive(o.rest_end_factor)) {
    throw core::InputError(kDetectorWhere, "rest_probe_s and rest_end_factor must be positive");
  }
  if (o.rule == ThresholdRule::kRestQuantile &&
      !(o.false_alarm > 0.0 && o.false_alarm < 0.5 && std::isfinite(o.min_multiple))) {
    throw core::InputError(kDetectorWhere, "false_alarm must lie in (0, 0.5)");
  }
  if (o.rule == ThresholdRule::kMultiple && !positive(o.threshold_multiple)) {
    throw core::InputError(kDetectorWhere, "threshold_multiple must be positive");
  }
  if (o.rule == ThresholdRule::kAbsolute && !positive(o.absolute_threshold)) {
    throw core::InputError(kDetectorWhere, "absolute_threshold must be positive");
  }
}

}  // namespace

std::vector<double> windowed_accel_variance(std::span<const core::ImuSample> samples,
                                            double window_s) {
  const std::size_t n = samples.size();
  std::vector<double> v(n, 0.0);
  if (n == 0) return v;
  // Prefix sums of the deviation from the first sample (keeps the sums small).
  const Eigen::Vector3d ref = samples[0].accel_mps2;
  std::vector<Eigen::Vector3d> s1(n + 1, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> s2(n + 1, Eigen::Vector3d::Zero());
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d d = samples[k].accel_mps2 - ref;
    s1[k + 1] = s1[k] + d;
    s2[k + 1] = s2[k] + d.cwiseAbs2();
  }
  const double half = 0.5 * window_s;
  std::size_t lo = 0, hi = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = samples[i].receive_time_s;
    while (lo < i && samples[lo].receive_time_s < t - half) ++lo;
    if (hi < i + 1) hi = i + 1;
    while (hi < n && samples[hi].receive_time_s <= t + half) ++hi;
    const double m = static_cast<double>(hi - lo);
    if (m < 2.0) continue;
    const Eigen::Vector3d sum = s1[hi] - s1[lo];
    const Eigen::Vector3d sq = s2[hi] - s2[lo];
    const Eigen::Vector3d var = (sq - sum.cwiseAbs2() / m) / (m - 1.0);
    v[i] = std::max(0.0, var.sum());
  }
  return v;
}

StaticDetection detect_static_intervals(std::span<const core::ImuSample> samples,
                                        const StaticDetectorOptions& o) {
  detector_check(o);
  const std::size_t n = samples.size();
  if (n < 3) throw core::InputError(kDetectorWhere, "fewer than 3 samples");
  for (std::size_t k = 1; k < n; ++k) {
    if (!(samples[k].receive_time_s > samples[k - 1].receive_time_s)) {
      throw core::InputError(kDetectorWhere,
                             fmt::format("time stamps do not increase at sample {}", k));
    }
  }
  const double t0 = samples.front().receive_time_s;
  const double span_s = samples.back().receive_time_s - t0;
  if (span_s < 3.0 * o.window_s) {
    throw core::InputError(kDetectorWhere,
                           fmt::format("the recording ({:.3g} s) is shorter than three "
                                       "windows of {:.3g} s",
                                       span_s, o.window_s));
  }
  const std::vector<double> v = windowed_accel_variance(samples, o.window_s);
  const double half = 0.5 * o.window_s;

  StaticDetection d;
  d.rule = o.rule;
  d.window_s = o.window_s;
  d.min_duration_s = o.min_duration_s;
  d.rest_start_s = t0;

  // The initial rest: given, or up to where v first leaves the quiet start.
  double rest_end = t0 + o.initial_rest_s;
  if (o.initial_rest_s <= 0.0) {
    std::vector<double> probe;
    for (std::size_t i = 0; i < n && samples[i].receive_time_s <= t0 + o.rest_probe_s; ++i) {
      if (samples[i].receive_time_s >= t0 + half) probe.push_back(v[i]);
    }
    if (probe.empty()) {
      throw core::InputError(kDetectorWhere, "rest_probe_s is shorter than half a window");
    }
    const double quiet = detector_median(probe);
    // A quiet start varies little; a start in motion spans orders of magnitude.
    const double loudest = *std::max_element(probe.begin(), probe.end());
    const double quietest = *std::min_element(probe.begin(), probe.end());
    if (loudest > o.rest_end_factor * quiet || quiet > o.rest_end_factor * quietest) {
      throw core::InputError(
          kDetectorWhere,
          fmt::format("the recording does not start at rest: within the first {:.3g} s the "
                      "accel variance varies by a factor {:.3g} (more than {:.3g}); record a "
                      "rest first, or give initial_rest_s",
                      o.rest_probe_s, loudest / std::max(quietest, 1e-30), o.rest_end_factor));
    }
    rest_end = samples.back().receive_time_s;
    for (std::size_t i = 0; i < n; ++i) {
      const double t = samples[i].receive_time_s;
      if (t < t0 + half) continue;
      if (v[i] > o.rest_end_factor * quiet) {
        rest_end = t + half;  // the window's leading edge met the motion
        break;
      }
    }
    d.rest_from_data = true;
  }
  d.rest_end_s = rest_end;
  // Rest windows wholly inside the rest.
  double sum = 0.0, sum_sq = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = samples[i].receive_time_s;
    if (t < t0 + half || t > rest_end - half) continue;
    sum += v[i];
    sum_sq += v[i] * v[i];
    ++count;
  }
  if (count < 3) {
    throw core::InputError(
        kDetectorWhere,
        fmt::format("the recording does not start at rest: the quiet start lasts "
                    "{:.3g} s, less than a window of {:.3g} s (give initial_rest_s, or "
                    "record a rest first)",
                    rest_end - t0, o.window_s));
  }
  const double rho = std::max(sum / static_cast<double>(count), 1e-30);
  const double var = std::max(0.0, sum_sq / static_cast<double>(count) - rho * rho);
  d.rest_level_mps2_sq = rho;
  d.rest_effective_dof = var > 0.0 ? 2.0 * rho * rho / var : 1e6;

  switch (o.rule) {
    case ThresholdRule::kRestQuantile: {
      const double nu = std::clamp(d.rest_effective_dof, 1.0, 1e6);
      const boost::math::chi_squared dist(nu);
      const double q = boost::math::quantile(boost::math::complement(dist, o.false_alarm)) / nu;
      d.threshold_multiple = std::max(o.min_multiple, q);
      d.rule_text = fmt::format(
          "{:.3g} x the rest level {:.3g} (m/s^2)^2: the rest's 1-{:.0e} quantile with {:.0f} "
          "effective degrees of freedom is {:.3g} x, the minimum multiple {:.3g} x",
          d.threshold_multiple, rho, o.false_alarm, nu, q, o.min_multiple);
      break;
    }
    case ThresholdRule::kMultiple:
      d.threshold_multiple = o.threshold_multiple;
      d.rule_text = fmt::format("{:.3g} x the rest level {:.3g} (m/s^2)^2 (given multiple)",
                                d.threshold_multiple, rho);
      break;
    case ThresholdRule::kAbsolute:
      d.threshold_multiple = o.absolute_threshold / rho;
      d.rule_text = fmt::format("{:.3g} (m/s^2)^2 given ({:.3g} x the rest level)",
                                o.absolute_threshold, d.threshold_multiple);
      break;
  }
  d.threshold_mps2_sq = d.threshold_multiple * rho;

  // Runs of static samples.
  std::size_t k = 0;
  while (k < n) {
    if (!(v[k] < d.threshold_mps2_sq)) {
      ++k;
      continue;
    }
    std::size_t e = k;
    while (e < n && v[e] < d.threshold_mps2_sq) ++e;
    StaticInterval in;
    in.begin = k;
    in.end = e;
    in.start_s = samples[k].receive_time_s;
    in.end_s = samples[e - 1].receive_time_s;
    if (in.duration_s() >= o.min_duration_s && e - k >= 3) {
      const double m = static_cast<double>(e - k);
      for (std::size_t j = k; j < e; ++j) {
        in.mean_accel_mps2 += samples[j].accel_mps2;
        in.mean_gyro_dps += samples[j].gyro_dps;
        in.mean_statistic += v[j];
      }
      in.mean_accel_mps2 /= m;
      in.mean_gyro_dps /= m;
      in.mean_statistic /= m;
      d.intervals.push_back(in);
    } else {
      ++d.rejected_short;
    }
    k = e;
  }
  if (!d.intervals.empty() && d.intervals.front().start_s <= t0 + o.window_s) {
    d.intervals.front().initial_rest = true;
    d.has_initial_rest = true;
  }
  return d;
}

nlohmann::json static_detection_to_json(const StaticDetection& d) {
  nlohmann::json j;
  j["window_s"] = d.window_s;
  j["min_duration_s"] = d.min_duration_s;
  j["rule"] = detector_rule_name(d.rule);
  j["rule_text"] = d.rule_text;
  j["threshold_mps2_sq"] = d.threshold_mps2_sq;
  j["threshold_multiple"] = d.threshold_multiple;
  j["rest"] = {{"start_s", d.rest_start_s},
               {"end_s", d.rest_end_s},
               {"from_data", d.rest_from_data},
               {"level_mps2_sq", d.rest_level_mps2_sq},
               {"effective_dof", d.rest_effective_dof}};
  j["rejected_short"] = d.rejected_short;
  nlohmann::json list = nlohmann::json::array();
  for (std::size_t i = 0; i < d.intervals.size(); ++i) {
    const StaticInterval& in = d.intervals[i];
    list.push_back(
        {{"index", i},
         {"begin", in.begin},
         {"end", in.end},
         {"start_s", in.start_s},
         {"end_s", in.end_s},
         {"duration_s", in.duration_s()},
         {"initial_rest", in.initial_rest},
         {"mean_accel_mps2",
          {in.mean_accel_mps2.x(), in.mean_accel_mps2.y(), in.mean_accel_mps2.z()}},
         {"mean_gyro_dps", {in.mean_gyro_dps.x(), in.mean_gyro_dps.y(), in.mean_gyro_dps.z()}},
         {"statistic_mps2_sq", in.mean_statistic}});
  }
  j["intervals"] = list;
  return j;
}

}  // namespace calstand::solver

// The record length each noise figure needs, from the edf of the Allan variance where the
// figure is read (the rule is in solver/record_length.hpp and docs/noise.md).
#include "noise/record_length.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "noise/edf.hpp"

namespace calstand::solver {
namespace {

// The longest record searched for [samples]: a year at 1 kHz.
constexpr double kMaxRecordSamples = 3.2e10;

// The largest tau of `curve` with at least min_edf degrees of freedom (where the curve is
// still well determined; NoiseTerms places the minimum among these points).
double longest_determined_tau(const AllanResult& curve, double min_edf) {
  double tau = 0.0;
  for (const AllanPoint& p : curve.points) {
    if (p.edf >= min_edf) tau = std::max(tau, p.tau_s);
  }
  return tau;
}

}  // namespace

double required_edf(const RecordLengthRule& rule) {
  const auto within = [&](double edf) {
    const DeviationInterval i = deviation_interval(1.0, edf, rule.confidence);
    return i.hi <= 1.0 + rule.half_width && i.lo >= 1.0 - rule.half_width;
  };
  double lo = 1.0;
  double hi = 2.0;
  while (!within(hi)) {
    lo = hi;
    hi *= 2.0;
  }
  for (int k = 0; k < 60 && hi - lo > 1e-3; ++k) {
    const double mid = 0.5 * (lo + hi);
    (within(mid) ? hi : lo) = mid;
  }
  return hi;
}

double record_length_for_edf(double tau_s, int alpha, double sample_rate_hz, double edf) {
  const auto m = static_cast<std::size_t>(std::max(1.0, std::round(tau_s * sample_rate_hz)));
  const auto edf_at = [&](double n) {
    return equivalent_dof(AllanKind::kAllan, alpha, m, static_cast<std::size_t>(n));
  };
  // edf grows with the record: double it until enough, then bisect on the sample count.
  double lo = static_cast<double>(2 * m);  // the shortest record with one difference term
  double hi = lo + 1.0;
  while (edf_at(hi) < edf && hi < kMaxRecordSamples) {
    lo = hi;
    hi *= 2.0;
  }
  while (hi - lo > std::max(1.0, 1e-4 * hi)) {
    const double mid = std::floor(0.5 * (lo + hi));
    (edf_at(mid) >= edf ? hi : lo) = mid;
  }
  return (hi - 1.0) / sample_rate_hz;
}

std::vector<FigureRecordNeed> record_length_needs(const RunNoise& noise,
                                                  const RecordLengthRule& rule) {
  const double edf = required_edf(rule);
  std::vector<FigureRecordNeed> out;
  for (const bool gyro : {true, false}) {
    for (const char* figure : {"random_walk", "bias_instability", "rate_random_walk"}) {
      FigureRecordNeed worst;
      bool any = false;
      for (const ChannelNoise& c : noise.channels) {
        if (is_gyro(c.channel) != gyro || c.allan.points.empty()) continue;
        FigureRecordNeed need;
        need.figure = figure;
        need.gyro = gyro;
        need.channel = std::string(to_string(c.channel));
        const std::string f = figure;
        const double longest = longest_determined_tau(c.allan, rule.min_points_edf);
        const double tau_min = c.terms.min_tau_s > 0.0 ? c.terms.min_tau_s : longest;
        // The minimum at the longest well-determined tau: the curve still falls there.
        const bool min_located = tau_min < longest;
        if (f == "random_walk") {
          need.tau_s = std::max(1.0, 1.0 / noise.sample_rate_hz);
          need.alpha = 0;
        } else if (f == "bias_instability") {
          need.tau_s = tau_min;
          need.alpha = -1;
          need.located = min_located;
        } else {
          need.tau_s = rule.rrw_tau_factor * tau_min;
          need.alpha = -2;
          need.located = min_located;
        }
        need.needed_s = record_length_for_edf(need.tau_s, need.alpha, noise.sample_rate_hz, edf);
        need.record_length_s = noise.duration_s;
        need.enough = need.located && need.record_length_s >= need.needed_s;
        const bool located = (!any || worst.located) && need.located;
        if (!any || need.needed_s > worst.needed_s) worst = need;
        worst.located = located;
        worst.enough = located && worst.record_length_s >= worst.needed_s;
        any = true;
      }
      if (any) out.push_back(worst);
    }
  }
  return out;
}

std::string format_record_length(double seconds) {
  if (!std::isfinite(seconds)) return "?";
  if (seconds < 120.0) return fmt::format("{:.0f} s", seconds);
  if (seconds < 2.0 * 3600.0) return fmt::format("{:.0f} min", seconds / 60.0);
  if (seconds < 2.0 * 86400.0) return fmt::format("{:.1f} h", seconds / 3600.0);
  return fmt::format("{:.1f} d", seconds / 86400.0);
}

}  // namespace calstand::solver

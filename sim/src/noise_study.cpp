#include "sim/noise_study.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string_view>

#include "sim/noise.hpp"

namespace calstand::sim {

namespace {

constexpr double kSecondsPerHour = 3600.0;

[[noreturn]] void throw_option(std::string_view option, std::string_view rule, double value) {
  throw std::invalid_argument(
      fmt::format("NoiseStudyOptions::{} must be {} (got {})", option, rule, value));
}

bool finite_positive(double x) { return std::isfinite(x) && x > 0.0; }

// Samples per run (the duration is rounded to whole samples).
long long sample_count(const NoiseStudyOptions& o) {
  return std::llround(o.duration_s * o.sample_rate_hz);
}

void validate(const NoiseStudyOptions& o) {
  if (o.runs < 2) throw_option("runs", ">= 2 (a spread across runs needs two)", o.runs);
  if (!finite_positive(o.white_sigma_dph))
    throw_option("white_sigma_dph", "> 0", o.white_sigma_dph);
  if (!finite_positive(o.sample_rate_hz)) throw_option("sample_rate_hz", "> 0", o.sample_rate_hz);
  if (!finite_positive(o.duration_s)) throw_option("duration_s", "> 0", o.duration_s);
  // 1e12 samples per run is days of computing; anything above is a typo, and the bound keeps
  // the sample count exact in a double.
  if (o.duration_s * o.sample_rate_hz < 1.0 || o.duration_s * o.sample_rate_hz > 1e12) {
    throw_option("duration_s", "between one sample and 1e12 samples", o.duration_s);
  }
  if (o.filter_order < 2 || o.filter_order > 8 || o.filter_order % 2 != 0) {
    throw_option("filter_order", "2, 4, 6 or 8", o.filter_order);
  }
  for (const double fc : o.cutoffs_hz) {
    if (!finite_positive(fc) || fc >= 0.5 * o.sample_rate_hz) {
      throw_option("cutoffs_hz", "in (0, sample_rate_hz / 2)", fc);
    }
  }
  const long long n = sample_count(o);
  for (const double t : o.walk_times_s) {
    const long long k = std::isfinite(t) ? std::llround(t * o.sample_rate_hz) : -1;
    if (!(t > 0.0) || k < 1 || k > n) {
      throw_option("walk_times_s", "in [one sample, duration_s]", t);
    }
  }
  for (const double tau : o.gm_taus_s) {
    if (!finite_positive(tau)) throw_option("gm_taus_s", "> 0", tau);
  }
}

struct GaussMarkovLane {
  double phi;    // exp(-dt / tau)
  double gain;   // c: scales the raw white sample into the drive
  double sigma;  // stationary sigma [deg/h]
};

}  // namespace

NoiseStudyResult run_noise_study(const NoiseStudyOptions& options) {
  validate(options);
  const NoiseStudyOptions& o = options;
  const double fs = o.sample_rate_hz;
  const double dt = 1.0 / fs;
  const double sigma_w = o.white_sigma_dph;
  const long long n = sample_count(o);
  const auto runs = static_cast<std::size_t>(o.runs);

  std::vector<ButterworthLowPass> filter_prototypes;
  for (const double fc : o.cutoffs_hz) filter_prototypes.emplace_back(o.filter_order, fc, fs);

  // The raw samples are the increments of the Gauss-Markov process: their variance sigma_w^2 is
  // q dt for a driving white noise of PSD q. The exact discretisation needs increments of
  // variance (q tau / 2)(1 - phi^2), hence c^2 = (tau / 2dt)(1 - phi^2) -> 1 for dt << tau.
  const double q = sigma_w * sigma_w * fs;  // sigma_w^2 / dt
  std::vector<GaussMarkovLane> lanes;
  for (const double tau : o.gm_taus_s) {
    const double one_minus_phi2 = -std::expm1(-2.0 * dt / tau);
    lanes.push_back({std::exp(-dt / tau), std::sqrt(tau / (2.0 * dt) * one_minus_phi2),
                     std::sqrt(q * tau / 2.0)});
  }

  // Walk checkpoints in time order, remembering which row each one fills.
  std::vector<std::size_t> walk_order(o.walk_times_s.size());
  for (std::size_t i = 0; i < walk_order.size(); ++i) walk_order[i] = i;
  std::vector<long long> walk_index(o.walk_times_s.size());
  for (std::size_t i = 0; i < walk_index.size(); ++i) {
    walk_index[i] = std::llround(o.walk_times_s[i] * fs);
  }
  std::sort(walk_order.begin(), walk_order.end(),
            [&](std::size_t a, std::size_t b) { return walk_index[a] < walk_index[b]; });

  double raw_sum_sq = 0.0;
  std::vector<double> filtered_sum_sq(filter_prototypes.size(), 0.0);
  std::vector<std::vector<double>> walk_sums(walk_index.size(), std::vector<double>(runs));
  std::vector<double> gm_sum_sq(lanes.size(), 0.0);
  std::vector<double> gm_within_sigma_sum(lanes.size(), 0.0);

  // Work in blocks: each stage then runs a tight loop over a cache-resident buffer, and the
  // per-block partial sums keep the rounding of the long accumulations small.
  constexpr std::size_t kBlock = 4096;
  constexpr std::size_t kLaneGroup = 4;
  std::array<double, kBlock> raw{};

  for (std::size_t run = 0; run < runs; ++run) {
    NormalSource white(derive_seed(o.seed, "noise_study.white", run));
    NormalSource start(derive_seed(o.seed, "noise_study.gm_start", run));
    std::vector<ButterworthLowPass> filters = filter_prototypes;  // at rest, like Matlab filter()
    std::vector<double> gm_state(lanes.size());
    std::vector<double> gm_origin(lanes.size());  // run sums are taken about x_0 (no cancellation)
    std::vector<double> gm_run_sum(lanes.size(), 0.0);
    std::vector<double> gm_run_sum_sq(lanes.size(), 0.0);
    for (std::size_t j = 0; j < lanes.size(); ++j) {
      gm_state[j] = lanes[j].sigma * start.next();  // stationary from the first sample
      gm_origin[j] = gm_state[j];
    }
    double walk = 0.0;  // running sum of raw samples [deg/h]; times dt/3600 gives deg
    std::size_t next_walk = 0;

    for (long long begin = 0; begin < n; begin += static_cast<long long>(kBlock)) {
      const auto len = static_cast<std::size_t>(std::min<long long>(kBlock, n - begin));
      double block_sq = 0.0;
      for (std::size_t i = 0; i < len; ++i) {
        raw[i] = sigma_w * white.next();
        block_sq += raw[i] * raw[i];
      }
      raw_sum_sq += block_sq;

      // Sample-major over the filters: their recursions are independent, so the processor
      // overlaps them instead of waiting on one filter's feedback latency at a time.
      for (std::size_t i = 0; i < len; ++i) {
        const double x = raw[i];
        for (std::size_t f = 0; f < filters.size(); ++f) {
          const double y = filters[f].filter(x);
          filtered_sum_sq[f] += y * y;
        }
      }

      // Angle random walk: checkpoints fall inside blocks, so sum up to each one.
      std::size_t i = 0;
      const long long end = begin + static_cast<long long>(len);
      while (next_walk < walk_order.size() && walk_index[walk_order[next_walk]] <= end) {
        const auto stop = static_cast<std::size_t>(walk_index[walk_order[next_walk]] - begin);
        for (; i < stop; ++i) walk += raw[i];
        walk_sums[walk_order[next_walk]][run] = walk;
        ++next_walk;
      }
      for (; i < len; ++i) walk += raw[i];

      // Four lanes at a time in registers, for the same reason as the filters.
      for (std::size_t j0 = 0; j0 < lanes.size(); j0 += kLaneGroup) {
        std::array<double, kLaneGroup> phi{}, gain{}, origin{}, x{}, s1{}, s2{};
        const std::size_t width = std::min(kLaneGroup, lanes.size() - j0);
        for (std::size_t l = 0; l < width; ++l) {
          phi[l] = lanes[j0 + l].phi;
          gain[l] = lanes[j0 + l].gain;
          origin[l] = gm_origin[j0 + l];
          x[l] = gm_state[j0 + l];
        }
        for (std::size_t k = 0; k < len; ++k) {
          const double w = raw[k];
          for (std::size_t l = 0; l < kLaneGroup; ++l) {  // unused lanes stay at zero
            x[l] = phi[l] * x[l] + gain[l] * w;
            const double d = x[l] - origin[l];
            s1[l] += d;
            s2[l] += d * d;
          }
        }
        for (std::size_t l = 0; l < width; ++l) {
          gm_state[j0 + l] = x[l];
          gm_run_sum[j0 + l] += s1[l];
          gm_run_sum_sq[j0 + l] += s2[l];
        }
      }
    }

    const auto nd = static_cast<double>(n);
    for (std::size_t j = 0; j < lanes.size(); ++j) {
      const double mean_d = gm_run_sum[j] / nd;
      const double var_within = std::max(0.0, gm_run_sum_sq[j] / nd - mean_d * mean_d);
      gm_within_sigma_sum[j] += std::sqrt(var_within);
      // Sum of x^2 from the sums about the origin: x = origin + d.
      const double origin = gm_origin[j];
      gm_sum_sq[j] += gm_run_sum_sq[j] + 2.0 * origin * gm_run_sum[j] + nd * origin * origin;
    }
  }

  const double total = static_cast<double>(n) * static_cast<double>(runs);
  const double runs_d = static_cast<double>(runs);
  NoiseStudyResult result;
  result.white.push_back({0.5 * fs, std::sqrt(raw_sum_sq / total), sigma_w, sigma_w});
  for (std::size_t f = 0; f < filter_prototypes.size(); ++f) {
    const ButterworthLowPass& lp = filter_prototypes[f];
    result.white.push_back({o.cutoffs_hz[f], std::sqrt(filtered_sum_sq[f] / total),
                            sigma_w * std::sqrt(lp.white_noise_power_gain()),
                            sigma_w * std::sqrt(lp.noise_equivalent_bandwidth_hz() / (0.5 * fs))});
  }

  const double to_deg = dt / kSecondsPerHour;  // sum of deg/h samples -> deg
  for (std::size_t w = 0; w < walk_index.size(); ++w) {
    double mean = 0.0;
    for (const double s : walk_sums[w]) mean += s;
    mean /= runs_d;
    double ss = 0.0;
    for (const double s : walk_sums[w]) ss += (s - mean) * (s - mean);
    const double sigma = std::sqrt(ss / (runs_d - 1.0)) * to_deg;
    // k samples of sigma_w [deg/h] times dt [s]: sigma_w / 3600 * dt * sqrt(k) [deg].
    const double theory =
        sigma_w / kSecondsPerHour * dt * std::sqrt(static_cast<double>(walk_index[w]));
    result.random_walk.push_back({o.walk_times_s[w], sigma, theory});
  }

  for (std::size_t j = 0; j < lanes.size(); ++j) {
    result.gauss_markov.push_back({o.gm_taus_s[j], q, std::sqrt(gm_sum_sq[j] / total),
                                   lanes[j].sigma, gm_within_sigma_sum[j] / runs_d});
  }
  return result;
}

}  // namespace calstand::sim

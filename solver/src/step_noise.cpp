#include "solver/step_noise.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace calstand::solver {
namespace {

// Components per decade of the flicker kernel: the covariance of interval means of one
// Gauss-Markov process is smooth over a decade in tau, so three per decade keep the sum's
// ripple well under the few per cent that the data could ever resolve.
constexpr double kFlickerComponentsPerDecade = 3.0;

/// (1 - e^{-x}) / x, which tends to 1 as x -> 0.
double one_minus_exp_over(double x) { return x < 1e-12 ? 1.0 - 0.5 * x : -std::expm1(-x) / x; }

/// Variance of the mean over an interval of x correlation times of a unit Gauss-Markov
/// process: 2 (x - 1 + e^{-x}) / x^2, by its series where the closed form cancels.
double gm_mean_variance_unit(double x) {
  if (x < 1e-4) return 1.0 - x / 3.0 + x * x / 12.0;
  return 2.0 * (x + std::expm1(-x)) / (x * x);
}

double gm_covariance(double sigma2, double tau, double a0, double a1, double b0, double b1) {
  if (a0 == b0 && a1 == b1) return sigma2 * gm_mean_variance_unit((a1 - a0) / tau);
  if (b0 < a0) {
    std::swap(a0, b0);
    std::swap(a1, b1);
  }
  const double gap = std::max(0.0, b0 - a1);
  return sigma2 * std::exp(-gap / tau) * one_minus_exp_over((a1 - a0) / tau) *
         one_minus_exp_over((b1 - b0) / tau);
}

/// Mean over [a0, a1] x [b0, b1] of min(s, t): the covariance of interval means of a unit
/// random walk started at 0.
double random_walk_covariance(double a0, double a1, double b0, double b1) {
  if (a0 == b0 && a1 == b1) return a0 + (a1 - a0) / 3.0;
  if (b0 < a0) {
    std::swap(a0, b0);
    std::swap(a1, b1);
  }
  return 0.5 * (a0 + a1);  // every s of the earlier interval is below every t of the later one
}

}  // namespace

std::string_view to_string(WanderKind kind) {
  switch (kind) {
    case WanderKind::kNone:
      return "none";
    case WanderKind::kGaussMarkov:
      return "gauss_markov";
    case WanderKind::kFlicker:
      return "flicker";
    case WanderKind::kRandomWalk:
      return "random_walk";
    case WanderKind::kSum:
      return "sum";
  }
  return "none";
}

double WanderModel::interval_mean_covariance(double a0, double a1, double b0, double b1) const {
  switch (kind) {
    case WanderKind::kNone:
      return 0.0;
    case WanderKind::kGaussMarkov:
      return gm_covariance(sigma * sigma, tau_s, a0, a1, b0, b1);
    case WanderKind::kRandomWalk:
      return random_walk_k * random_walk_k * random_walk_covariance(a0, a1, b0, b1);
    case WanderKind::kFlicker: {
      // 1/f noise as equal-variance Gauss-Markov processes, log-spaced by the ratio r: their
      // two-sided spectra 2 v tau / (1 + (2 pi f tau)^2) sum to v / (2 f ln r) inside the
      // band, which is IEEE 952's B^2 / (2 pi f) for v = B^2 ln r / pi.
      const double decades = std::log10(tau_max_s / tau_min_s);
      const int count =
          std::max(2, static_cast<int>(std::ceil(kFlickerComponentsPerDecade * decades)) + 1);
      const double log_ratio = std::log(tau_max_s / tau_min_s) / (count - 1);
      const double v = flicker_b * flicker_b * log_ratio / std::numbers::pi;
      double sum = 0.0;
      for (int k = 0; k < count; ++k) {
        sum += gm_covariance(v, tau_min_s * std::exp(log_ratio * k), a0, a1, b0, b1);
      }
      return sum;
    }
    case WanderKind::kSum: {
      double sum = 0.0;
      for (const WanderModel& p : parts) sum += p.interval_mean_covariance(a0, a1, b0, b1);
      return sum;
    }
  }
  return 0.0;
}

StepNoise StepNoise::white_only(const NoiseFloor& floor, const std::string& why) {
  StepNoise n;
  n.white = floor;
  n.method = why;
  for (auto& c : n.channels) {
    c.determined = false;
    c.source = "white noise inside the steps only";
    c.note = why;
  }
  return n;
}

Eigen::MatrixXd StepNoise::covariance(int channel, const std::vector<StepSummary>& steps) const {
  const auto n = static_cast<Eigen::Index>(steps.size());
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, n);
  const WanderModel& w = channels[static_cast<std::size_t>(channel)].wander;
  for (Eigen::Index i = 0; i < n; ++i) {
    const StepSummary& si = steps[static_cast<std::size_t>(i)];
    C(i, i) = white.density[channel] / static_cast<double>(si.count);
    if (w.kind == WanderKind::kNone) continue;
    for (Eigen::Index j = 0; j <= i; ++j) {
      const StepSummary& sj = steps[static_cast<std::size_t>(j)];
      const double c = w.interval_mean_covariance(si.start_s, si.end_s, sj.start_s, sj.end_s);
      C(i, j) += c;
      if (j != i) C(j, i) += c;
    }
  }
  return C;
}

bool StepNoise::correlated() const {
  return std::any_of(channels.begin(), channels.end(),
                     [](const ChannelStepNoise& c) { return c.wander.kind != WanderKind::kNone; });
}

nlohmann::json wander_to_json(const WanderModel& wander) {
  nlohmann::json w{{"kind", to_string(wander.kind)}};
  switch (wander.kind) {
    case WanderKind::kGaussMarkov:
      w["sigma"] = wander.sigma;
      w["tau_s"] = wander.tau_s;
      break;
    case WanderKind::kFlicker:
      w["b"] = wander.flicker_b;
      w["allan_floor"] = wander.flicker_b * std::sqrt(2.0 * std::numbers::ln2 / std::numbers::pi);
      w["tau_min_s"] = wander.tau_min_s;
      w["tau_max_s"] = wander.tau_max_s;
      break;
    case WanderKind::kRandomWalk:
      w["k"] = wander.random_walk_k;
      break;
    case WanderKind::kSum:
      w["parts"] = nlohmann::json::array();
      for (const WanderModel& p : wander.parts) w["parts"].push_back(wander_to_json(p));
      break;
    case WanderKind::kNone:
      break;
  }
  return w;
}

nlohmann::json step_noise_to_json(const StepNoise& noise, double sample_rate_hz) {
  nlohmann::json j;
  j["method"] = noise.method;
  j["white_from"] = noise.white.from_static_steps ? "static steps" : "all steps";
  j["white_steps"] = noise.white.steps_used;
  j["channels"] = nlohmann::json::array();
  for (int c = 0; c < kChannels; ++c) {
    const ChannelStepNoise& ch = noise.channels[static_cast<std::size_t>(c)];
    const std::string unit = c < kAx ? "deg/s" : "m/s^2";
    nlohmann::json e;
    e["channel"] = channel_name(c);
    e["unit"] = unit;
    // The white part as a density [u/sqrt(Hz)]: the per-sample variance times the sample period.
    e["white_density"] = sample_rate_hz > 0.0 ? std::sqrt(noise.white.density[c] / sample_rate_hz)
                                              : std::numeric_limits<double>::quiet_NaN();
    e["wander"] = wander_to_json(ch.wander);
    e["determined"] = ch.determined;
    e["source"] = ch.source;
    if (!ch.note.empty()) e["note"] = ch.note;
    j["channels"].push_back(std::move(e));
  }
  return j;
}

}  // namespace calstand::solver

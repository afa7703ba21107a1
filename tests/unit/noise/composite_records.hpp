#pragma once
// Static records of composite noise by exact discrete-time recursions, shared by the noise-id
// acceptance test (composite_noise_test.cpp) and its table (bench/noise_id_bench.cpp).

#include <cmath>
#include <random>
#include <vector>

#include "noise/composite_noise.hpp"

namespace calstand::solver::testing {

inline constexpr double kCompositeRateHz = 100.0;

/// One simulated term: white density N, Gauss-Markov sigma (with tau_s), random walk K.
struct TrueTerm {
  NoiseKind kind;
  double value;
  double tau_s = 0.0;
};

/// `n` samples at kCompositeRateHz. Exact recursions: white y = N sqrt(fs) w; Gauss-Markov
/// x' = phi x + sigma sqrt(1 - phi^2) w from its stationary law; random walk r' = r + K
/// sqrt(1/fs) w.
inline std::vector<double> simulate_composite(const std::vector<TrueTerm>& truth, std::size_t n,
                                              unsigned seed) {
  const double fs = kCompositeRateHz;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<double> y(n, 0.0);
  for (const TrueTerm& t : truth) {
    if (t.kind == NoiseKind::kWhite) {
      for (double& v : y) v += t.value * std::sqrt(fs) * g(rng);
    } else if (t.kind == NoiseKind::kGaussMarkov) {
      const double phi = std::exp(-1.0 / (fs * t.tau_s));
      double x = t.value * g(rng);
      for (double& v : y) {
        v += x;
        x = phi * x + t.value * std::sqrt(1.0 - phi * phi) * g(rng);
      }
    } else if (t.kind == NoiseKind::kRandomWalk) {
      double r = 0.0;
      for (double& v : y) {
        r += t.value / std::sqrt(fs) * g(rng);
        v += r;
      }
    }
  }
  return y;
}

}  // namespace calstand::solver::testing

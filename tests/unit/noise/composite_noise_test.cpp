// Composite noise identification (GMWM) on records simulated with exact discrete-time recursions
// (a simulator written here, independent of the bootstrap's): the issue 33 acceptance models,
// three seeds and two lengths each. The full table, and the Allan-line fit's, come from
// bench/noise_id_bench.cpp (docs/noise-id.md).
#include "noise/composite_noise.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "composite_records.hpp"
#include "core/error.hpp"

namespace calstand::solver {
namespace {

constexpr double kFs = testing::kCompositeRateHz;  // Hz

using testing::TrueTerm;

std::vector<double> simulate(const std::vector<TrueTerm>& truth, std::size_t n, unsigned seed) {
  return testing::simulate_composite(truth, n, seed);
}

// Flicker as a sum of Gauss-Markov processes a factor of 2 apart in correlation time, equal
// sigmas: flat Allan variance between its ends.
std::vector<TrueTerm> flicker_bank(double sigma_each) {
  std::vector<TrueTerm> bank;
  for (double tc = 0.05; tc < 5000.0; tc *= 2.0)
    bank.push_back({NoiseKind::kGaussMarkov, sigma_each, tc});
  return bank;
}

struct Scenario {
  const char* name;
  std::vector<TrueTerm> truth;      // the parameters to recover
  std::vector<TrueTerm> extra;      // simulated but not a named term (the flicker bank)
  std::vector<NoiseKind> true_set;  // the terms to be selected
};

std::vector<Scenario> scenarios() {
  using K = NoiseKind;
  return {
      {"white + GM + RW",
       {{K::kWhite, 0.005}, {K::kGaussMarkov, 0.004, 2.0}, {K::kRandomWalk, 5e-4}},
       {},
       {K::kWhite, K::kGaussMarkov, K::kRandomWalk}},
      {"white + two GM",
       {{K::kWhite, 0.005}, {K::kGaussMarkov, 0.004, 0.5}, {K::kGaussMarkov, 0.003, 100.0}},
       {},
       {K::kWhite, K::kGaussMarkov, K::kGaussMarkov}},
      {"white + RW", {{K::kWhite, 0.005}, {K::kRandomWalk, 5e-4}}, {}, {K::kWhite, K::kRandomWalk}},
      {"white + flicker + RW",
       {{K::kWhite, 0.005}, {K::kRandomWalk, 5e-4}},
       flicker_bank(0.0011),
       {K::kWhite, K::kFlicker, K::kRandomWalk}},
  };
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? std::nan("") : v[v.size() / 2];
}

// Issue 33's bars on the four models, three seeds and two lengths (2^19 and 2^20 samples at
// 100 Hz, 87 and 175 min): the true set in at least 5 of 6 records of each model, the truth in
// the 95 % interval for at least 90 % of the parameters of the records whose set was right,
// median relative error of a Gauss-Markov sigma and tau under 15 %, of a white density under
// 2 %. About 20 s of CPU. At 2^18 samples (44 min) the random walk under flicker is too weak
// for 5 of 6 (bench/noise_id_bench.cpp's table in docs/noise-id.md shows it).
TEST(CompositeNoise, AcceptanceOnSimulatedModels) {
  std::size_t covered = 0, checked = 0;
  std::vector<double> gm_sigma_err, gm_tau_err, white_err;
  unsigned model_index = 0;
  for (const Scenario& s : scenarios()) {
    ++model_index;
    int right_set = 0;
    for (std::size_t n : {std::size_t{1} << 19, std::size_t{1} << 20}) {
      for (unsigned seed : {1u, 2u, 3u}) {
        std::vector<TrueTerm> all = s.truth;
        all.insert(all.end(), s.extra.begin(), s.extra.end());
        // A seed per model too: the same seed would give every model the same white noise,
        // and one white realisation would count four times.
        const std::vector<double> y =
            simulate(all, n, seed * 7919u + static_cast<unsigned>(n) + 104729u * model_index);
        const NoiseModel m = identify_noise_model(y, kFs);
        std::vector<NoiseKind> got;
        for (const auto& t : m.terms) got.push_back(t.kind);
        const bool same = got == s.true_set;
        right_set += same ? 1 : 0;
        if (!same) continue;
        // Match the named true terms to the estimates in order (both sorted by kind, then tau).
        std::vector<TrueTerm> truth = s.truth;
        std::sort(truth.begin(), truth.end(), [](const TrueTerm& a, const TrueTerm& b) {
          return a.kind != b.kind ? a.kind < b.kind : a.tau_s < b.tau_s;
        });
        std::size_t k = 0;
        for (const NoiseModelTerm& e : m.terms) {
          if (e.kind == NoiseKind::kFlicker) continue;  // the bank has no single true B
          const TrueTerm& t = truth[k++];
          ASSERT_EQ(t.kind, e.kind);
          ++checked;
          covered += t.value >= e.value_lo && t.value <= e.value_hi ? 1 : 0;
          if (e.kind == NoiseKind::kGaussMarkov) {
            ++checked;
            covered += t.tau_s >= e.tau_lo_s && t.tau_s <= e.tau_hi_s ? 1 : 0;
            gm_sigma_err.push_back(std::abs(e.value / t.value - 1.0));
            gm_tau_err.push_back(std::abs(e.tau_s / t.tau_s - 1.0));
          }
          if (e.kind == NoiseKind::kWhite) white_err.push_back(std::abs(e.value / t.value - 1.0));
        }
      }
    }
    EXPECT_GE(right_set, 5) << s.name << ": true set selected in " << right_set << " of 6";
  }
  std::printf(
      "%zu of %zu true parameters inside their 95 %% intervals; median GM sigma error "
      "%.3f, tau %.3f, white density %.4f\n",
      covered, checked, median(gm_sigma_err), median(gm_tau_err), median(white_err));
  ASSERT_GT(checked, 20u);
  EXPECT_GE(static_cast<double>(covered) / static_cast<double>(checked), 0.9)
      << covered << " of " << checked << " true parameters inside their 95 % intervals";
  EXPECT_LT(median(gm_sigma_err), 0.15);
  EXPECT_LT(median(gm_tau_err), 0.15);
  EXPECT_LT(median(white_err), 0.02);
}

// The wavelet variance of each term against its definition computed by brute force from the
// autocovariance (AR(1) and random walk) and closed forms (IEEE Std 952).
TEST(CompositeNoise, TermWaveletVariances) {
  const double fs = 10.0;
  // White: Allan variance N^2 / tau, wavelet variance half of it.
  EXPECT_NEAR(term_wavelet_variance(NoiseKind::kWhite, 0.3, 0, 8, fs), 0.5 * 0.09 / 0.8, 1e-15);
  // Random walk: K^2 tau / 3 for long tau.
  EXPECT_NEAR(
      term_wavelet_variance(NoiseKind::kRandomWalk, 0.2, 0, 4096, fs) / (0.5 * 0.04 * 409.6 / 3.0),
      1.0, 1e-6);
  // Gauss-Markov against a direct double sum of its autocovariance sigma^2 phi^|h|.
  for (std::size_t m : {1u, 3u, 50u}) {
    const double sigma = 1.5, tc = 2.0, phi = std::exp(-1.0 / (fs * tc));
    double var_mean = 0.0, cov = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
      for (std::size_t j = 0; j < m; ++j) {
        var_mean += std::pow(phi, std::abs(static_cast<double>(i) - static_cast<double>(j)));
        cov += std::pow(phi, static_cast<double>(m + j - i));
      }
    }
    const double avar = sigma * sigma * (var_mean - cov) / static_cast<double>(m * m);
    EXPECT_NEAR(term_wavelet_variance(NoiseKind::kGaussMarkov, sigma, tc, m, fs) / (0.5 * avar),
                1.0, 1e-9)
        << m;
  }
}

// The parametric-bootstrap intervals with the first scales left out: white + random walk, 2^16
// samples, 40 replicates; each interval holds its estimate and, here, the truth.
TEST(CompositeNoise, BootstrapIntervalsWithMinTau) {
  const std::vector<TrueTerm> truth{{NoiseKind::kWhite, 0.005}, {NoiseKind::kRandomWalk, 5e-4}};
  const std::vector<double> y = simulate(truth, std::size_t{1} << 16, 17u);
  NoiseIdOptions o;
  o.bootstrap = 40;
  o.min_tau_s = 0.04;  // from m = 4 at 100 Hz
  const NoiseModel m = identify_noise_model(y, kFs, o);
  EXPECT_EQ(m.moments.m.front(), 4u);
  ASSERT_EQ(m.terms.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const NoiseModelTerm& t = m.terms[k];
    EXPECT_EQ(t.kind, truth[k].kind);
    EXPECT_LT(t.value_lo, t.value);
    EXPECT_GT(t.value_hi, t.value);
    EXPECT_LE(t.value_lo, truth[k].value);
    EXPECT_GE(t.value_hi, truth[k].value);
  }
  EXPECT_NE(m.estimator.find("40 parametric-bootstrap"), std::string::npos) << m.estimator;
}

TEST(CompositeNoise, BadInput) {
  EXPECT_THROW(identify_noise_model(std::vector<double>(20, 0.1), 100.0), core::InputError);
  std::vector<double> y(1000, 0.0);
  y[3] = std::nan("");
  EXPECT_THROW(identify_noise_model(y, 100.0), core::InputError);
  NoiseIdOptions o;
  o.bootstrap = 5;
  EXPECT_THROW(identify_noise_model(std::vector<double>(1000, 0.1), 100.0, o), core::InputError);
  NoiseIdOptions late;
  late.min_tau_s = 5.0;  // 1000 samples at 100 Hz: scales to m = 250, 2.5 s
  EXPECT_THROW(identify_noise_model(std::vector<double>(1000, 0.1), 100.0, late), core::InputError);
}

}  // namespace
}  // namespace calstand::solver

#include "sim/noise_study.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/noise.hpp"

// A reduced study (400 runs of 200 s: 8e7 samples, a few seconds) checked row by row. Every
// tolerance is kZ standard errors of the estimate, derived from the sampling statistics below,
// plus any stated model or start-up bias. The seed is fixed, so the test is deterministic.

namespace calstand::sim {
namespace {

constexpr double kZ = 4.0;

NoiseStudyOptions reduced_options() {
  NoiseStudyOptions o;
  o.runs = 400;
  o.duration_s = 200.0;
  o.walk_times_s = {10.0, 60.0, 200.0};
  o.seed = 2024;
  return o;  // sigma 0.03 deg/h, 1 kHz, order 2, cutoffs 100/10/1 Hz, taus 4/40/400/4000 s
}

/// Relative variance of the time average of x^2 over a run of length D for a stationary
/// Gauss-Markov x of correlation time tau: x^2 has autocovariance 2 sigma^4 exp(-2|t|/tau), and
/// the average of an exponentially correlated process over D has variance
/// (2 tau'/D)(1 - (tau'/D)(1 - exp(-D/tau'))) times its variance, tau' = tau/2. Tends to 2 (one
/// sample of sigma^2 chi^2_1) when tau >> D.
double gm_mean_square_rel_var(double tau, double d) {
  const double tp = 0.5 * tau;
  return 2.0 * (2.0 * tp / d) * (1.0 - tp / d * (-std::expm1(-d / tp)));
}

/// Variance of a Gauss-Markov run's mean over D, relative to sigma^2 (same formula with tau).
double gm_run_mean_rel_var(double tau, double d) {
  return (2.0 * tau / d) * (1.0 - tau / d * (-std::expm1(-d / tau)));
}

void check_raw_white_row(const NoiseStudyOptions& o, const NoiseStudyResult& r) {
  const WhiteNoiseRow& raw = r.white.front();
  EXPECT_EQ(raw.cutoff_hz, 0.5 * o.sample_rate_hz);
  EXPECT_EQ(raw.theory, o.white_sigma_dph);
  EXPECT_EQ(raw.theory_analog, o.white_sigma_dph);
  // RMS of N independent samples: relative sd 1/sqrt(2N) = 8e-5.
  const double n = o.runs * o.duration_s * o.sample_rate_hz;
  EXPECT_NEAR(raw.rms / raw.theory, 1.0, kZ / std::sqrt(2.0 * n));
}

void check_band_limited_rows(const NoiseStudyOptions& o, const NoiseStudyResult& r) {
  const double n = o.runs * o.duration_s * o.sample_rate_hz;
  const double half_fs = 0.5 * o.sample_rate_hz;
  for (std::size_t i = 0; i < o.cutoffs_hz.size(); ++i) {
    const WhiteNoiseRow& row = r.white[i + 1];
    const ButterworthLowPass lp(o.filter_order, o.cutoffs_hz[i], o.sample_rate_hz);
    const double enbw = lp.noise_equivalent_bandwidth_hz();
    EXPECT_EQ(row.cutoff_hz, o.cutoffs_hz[i]);
    // Theory: the exact variance gain of the digital filter; the analog figure beside it.
    EXPECT_NEAR(row.theory / (o.white_sigma_dph * std::sqrt(lp.white_noise_power_gain())), 1.0,
                1e-14);
    EXPECT_NEAR(row.theory_analog / (o.white_sigma_dph * std::sqrt(enbw / half_fs)), 1.0, 1e-14);
    // Sampling error: the mean square of filtered noise has relative variance
    // 2 sum_k rho_k^2 / N, and for a 2nd-order Butterworth sum rho^2 = 0.75 / beta with
    // beta = ENBW / (fs/2) (integral |H|^4 over integral |H|^2); half of it for the RMS.
    const double beta = enbw / half_fs;
    const double stat = 0.5 * std::sqrt(2.0 * 0.75 / (n * beta));
    // Each run starts the filters at rest: the output misses at most ~1/ENBW seconds of
    // variance per run, a relative deficit 1/(ENBW D) in the mean square (0.45 % at 1 Hz). It
    // can only lower the RMS, so it widens the band on that side alone.
    const double startup = 0.5 / (enbw * o.duration_s);
    EXPECT_LT(row.rms / row.theory - 1.0, kZ * stat) << "cutoff " << row.cutoff_hz;
    EXPECT_GT(row.rms / row.theory - 1.0, -(kZ * stat + startup)) << "cutoff " << row.cutoff_hz;
  }
}

void check_random_walk_rows(const NoiseStudyOptions& o, const NoiseStudyResult& r) {
  const double dt = 1.0 / o.sample_rate_hz;
  for (std::size_t i = 0; i < o.walk_times_s.size(); ++i) {
    const RandomWalkRow& row = r.random_walk[i];
    EXPECT_EQ(row.t_s, o.walk_times_s[i]);
    // sigma [deg/h] -> deg/s, times dt per sample, sqrt(t/dt) samples.
    EXPECT_NEAR(row.theory / (o.white_sigma_dph / 3600.0 * dt * std::sqrt(row.t_s / dt)), 1.0,
                1e-12);
    // Sample sd over R independent runs: relative sd 1/sqrt(2(R-1)) = 3.5 %.
    EXPECT_NEAR(row.sigma / row.theory, 1.0, kZ / std::sqrt(2.0 * (o.runs - 1))) << "t " << row.t_s;
  }
}

void check_gauss_markov_rows(const NoiseStudyOptions& o, const NoiseStudyResult& r) {
  const double q = o.white_sigma_dph * o.white_sigma_dph * o.sample_rate_hz;  // sigma^2 / dt
  for (std::size_t i = 0; i < o.gm_taus_s.size(); ++i) {
    const GaussMarkovRow& row = r.gauss_markov[i];
    EXPECT_EQ(row.tau_s, o.gm_taus_s[i]);
    EXPECT_NEAR(row.q / q, 1.0, 1e-12);
    EXPECT_NEAR(row.theory / std::sqrt(q * row.tau_s / 2.0), 1.0, 1e-12);
    // Pooled RMS over R stationary runs: relative sd 0.5 sqrt(rel_var / R); 0.5 % at 4 s, 3.5 %
    // at 4000 s where each run is about one correlated value.
    const double stat = 0.5 * std::sqrt(gm_mean_square_rel_var(row.tau_s, o.duration_s) / o.runs);
    EXPECT_NEAR(row.sigma / row.theory, 1.0, kZ * stat) << "tau " << row.tau_s;
  }
}

void check_within_run_sigma(const NoiseStudyOptions& o, const NoiseStudyResult& r) {
  // Within one run the de-meaned variance is sigma^2 (1 - v), v = var(run mean) / sigma^2.
  // The mean over runs of sqrt(s^2) lies below sqrt(E s^2) by the spread of s^2 (Jensen), up
  // to ~10 % when tau >> D where s^2 has few degrees of freedom, and within 4 sd of sampling
  // error above it; 15 % below covers both. The point of the row: tau = 4 s is white-like
  // (within-run sigma ~ sigma), tau = 4000 s random-walk-like (~13 % of sigma for D = 200 s).
  for (const GaussMarkovRow& row : r.gauss_markov) {
    const double expected =
        row.theory * std::sqrt(1.0 - gm_run_mean_rel_var(row.tau_s, o.duration_s));
    EXPECT_LT(row.within_run_sigma / expected, 1.05) << "tau " << row.tau_s;
    EXPECT_GT(row.within_run_sigma / expected, 0.85) << "tau " << row.tau_s;
    EXPECT_LE(row.within_run_sigma, row.sigma) << "tau " << row.tau_s;
  }
  EXPECT_GT(r.gauss_markov.front().within_run_sigma / r.gauss_markov.front().theory, 0.95);
  EXPECT_LT(r.gauss_markov.back().within_run_sigma / r.gauss_markov.back().theory, 0.2);
}

// One study for all row checks: gtest_discover_tests runs every TEST in its own process, so
// separate tests would each pay the few seconds the study takes.
TEST(NoiseStudy, ReducedStudyRowsMatchTheory) {
  const NoiseStudyOptions o = reduced_options();
  const NoiseStudyResult r = run_noise_study(o);
  ASSERT_EQ(r.white.size(), o.cutoffs_hz.size() + 1);
  ASSERT_EQ(r.random_walk.size(), o.walk_times_s.size());
  ASSERT_EQ(r.gauss_markov.size(), o.gm_taus_s.size());
  {
    SCOPED_TRACE("raw white noise");
    check_raw_white_row(o, r);
  }
  {
    SCOPED_TRACE("band-limited white noise");
    check_band_limited_rows(o, r);
  }
  {
    SCOPED_TRACE("angle random walk");
    check_random_walk_rows(o, r);
  }
  {
    SCOPED_TRACE("Gauss-Markov sigma");
    check_gauss_markov_rows(o, r);
  }
  {
    SCOPED_TRACE("Gauss-Markov within-run sigma");
    check_within_run_sigma(o, r);
  }
}

NoiseStudyOptions tiny_options(std::uint64_t seed) {
  NoiseStudyOptions o;
  o.runs = 3;
  o.duration_s = 5.0;
  o.walk_times_s = {1.0, 5.0};
  o.gm_taus_s = {1.0, 10.0};
  o.seed = seed;
  return o;
}

std::vector<double> flatten(const NoiseStudyResult& r) {
  std::vector<double> v;
  for (const auto& w : r.white) v.insert(v.end(), {w.cutoff_hz, w.rms, w.theory, w.theory_analog});
  for (const auto& w : r.random_walk) v.insert(v.end(), {w.t_s, w.sigma, w.theory});
  for (const auto& g : r.gauss_markov) {
    v.insert(v.end(), {g.tau_s, g.q, g.sigma, g.theory, g.within_run_sigma});
  }
  return v;
}

TEST(NoiseStudy, SameSeedSameResultOtherSeedOtherResult) {
  const NoiseStudyResult ra = run_noise_study(tiny_options(7));
  const NoiseStudyResult rb = run_noise_study(tiny_options(7));
  const NoiseStudyResult rc = run_noise_study(tiny_options(8));
  EXPECT_EQ(flatten(ra), flatten(rb));  // bit for bit
  // Every simulated value changes with the seed; the theory columns do not.
  for (std::size_t i = 0; i < ra.white.size(); ++i) {
    EXPECT_NE(ra.white[i].rms, rc.white[i].rms);
    EXPECT_EQ(ra.white[i].theory, rc.white[i].theory);
  }
  for (std::size_t i = 0; i < ra.random_walk.size(); ++i) {
    EXPECT_NE(ra.random_walk[i].sigma, rc.random_walk[i].sigma);
  }
  for (std::size_t i = 0; i < ra.gauss_markov.size(); ++i) {
    EXPECT_NE(ra.gauss_markov[i].sigma, rc.gauss_markov[i].sigma);
    EXPECT_NE(ra.gauss_markov[i].within_run_sigma, rc.gauss_markov[i].within_run_sigma);
    EXPECT_EQ(ra.gauss_markov[i].theory, rc.gauss_markov[i].theory);
  }
}

TEST(NoiseStudy, WalkTimesInAnyOrderFillTheirOwnRows) {
  NoiseStudyOptions sorted = tiny_options(3);
  NoiseStudyOptions reversed = sorted;
  reversed.walk_times_s = {5.0, 1.0};
  const NoiseStudyResult a = run_noise_study(sorted);
  const NoiseStudyResult b = run_noise_study(reversed);
  EXPECT_EQ(a.random_walk[0].sigma, b.random_walk[1].sigma);
  EXPECT_EQ(a.random_walk[1].sigma, b.random_walk[0].sigma);
  EXPECT_EQ(b.random_walk[0].t_s, 5.0);
}

TEST(NoiseStudy, BadOptionsThrowNamingTheOption) {
  struct Case {
    std::function<void(NoiseStudyOptions&)> spoil;
    const char* name;
  };
  const std::vector<Case> cases{
      {[](NoiseStudyOptions& o) { o.runs = 1; }, "runs"},
      {[](NoiseStudyOptions& o) { o.white_sigma_dph = 0.0; }, "white_sigma_dph"},
      {[](NoiseStudyOptions& o) { o.white_sigma_dph = std::nan(""); }, "white_sigma_dph"},
      {[](NoiseStudyOptions& o) { o.sample_rate_hz = -1.0; }, "sample_rate_hz"},
      {[](NoiseStudyOptions& o) { o.duration_s = 0.0; }, "duration_s"},
      {[](NoiseStudyOptions& o) { o.duration_s = 1e-4; }, "duration_s"},  // < one sample
      {[](NoiseStudyOptions& o) { o.filter_order = 3; }, "filter_order"},
      {[](NoiseStudyOptions& o) {
         o.cutoffs_hz = {10.0, 500.0};
       },
       "cutoffs_hz"},
      {[](NoiseStudyOptions& o) { o.cutoffs_hz = {0.0}; }, "cutoffs_hz"},
      {[](NoiseStudyOptions& o) {
         o.walk_times_s = {5.0, 6.0};
       },
       "walk_times_s"},
      {[](NoiseStudyOptions& o) { o.walk_times_s = {0.0}; }, "walk_times_s"},
      {[](NoiseStudyOptions& o) {
         o.gm_taus_s = {1.0, 0.0};
       },
       "gm_taus_s"},
  };
  for (const Case& c : cases) {
    NoiseStudyOptions o = tiny_options(1);
    c.spoil(o);
    std::string message;
    try {
      run_noise_study(o);
    } catch (const std::invalid_argument& e) {
      message = e.what();
    }
    EXPECT_NE(message.find(c.name), std::string::npos) << "'" << message << "' lacks " << c.name;
  }
  EXPECT_NO_THROW(run_noise_study(tiny_options(1)));
}

}  // namespace
}  // namespace calstand::sim

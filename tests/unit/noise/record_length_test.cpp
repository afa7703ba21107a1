// The record length each noise figure needs (solver/record_length.hpp): the edf rule itself,
// and a short and a long simulated static record with white noise, flicker and rate random walk.
#include "noise/record_length.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "noise/edf.hpp"
#include "noise/noise_fit.hpp"
#include "sim/noise.hpp"

namespace calstand::solver {
namespace {

constexpr int kStepsPerSample = 10;

// A rate [deg/s] at rate_hz: angle random walk N, bias instability B (flicker from 0.05 s to
// 1e5 s) and rate random walk K, each output sample the mean of kStepsPerSample simulator steps
// (an integrating sensor), as in noise_fit_test.cpp.
std::vector<double> simulate_static_rate(double n, double b, double k, double rate_hz,
                                         double duration_s, std::uint64_t seed) {
  const double fast_hz = rate_hz * kStepsPerSample;
  const double dt = 1.0 / fast_hz;
  sim::WhiteNoise white(n, fast_hz, sim::derive_seed(seed, "white"));
  sim::BiasInstability flicker(b, dt, sim::derive_seed(seed, "flicker"), 0.05, 1e5);
  sim::RandomWalk walk(k, dt, sim::derive_seed(seed, "walk"));
  std::vector<double> y(static_cast<std::size_t>(duration_s * rate_hz));
  for (double& v : y) {
    double sum = 0.0;
    for (int i = 0; i < kStepsPerSample; ++i) sum += white.next() + flicker.next() + walk.next();
    v = sum / kStepsPerSample;
  }
  return y;
}

// A RunNoise of one gyro channel (gx) from rate data, as analyse_run_noise() makes it.
RunNoise run_noise_of(const std::vector<double>& y, double rate_hz) {
  RunNoise r;
  r.sample_rate_hz = rate_hz;
  r.samples = y.size();
  r.duration_s = static_cast<double>(y.size() - 1) / rate_hz;
  ChannelNoise c;
  c.channel = ImuChannel::kGx;
  AllanOptions o;
  o.taus = TauSet::parse("dense");
  c.allan = allan(y, rate_hz, o);
  c.terms = fit_noise_terms(c.allan);
  r.channels.push_back(c);
  return r;
}

const FigureRecordNeed& need_of(const std::vector<FigureRecordNeed>& needs, const char* figure) {
  for (const auto& n : needs) {
    if (n.figure == figure) return n;
  }
  throw std::runtime_error(figure);
}

TEST(RecordLength, TheRequiredEdfIsTheSmallestThatGivesTheInterval) {
  const double e = required_edf();
  const DeviationInterval at = deviation_interval(1.0, e, 0.95);
  EXPECT_LE(at.hi, 1.25);
  EXPECT_GE(at.lo, 0.75);
  // The upper end binds (a chi-square interval of a deviation is wider above): 1 % fewer
  // degrees of freedom give an interval reaching past +25 %.
  EXPECT_GT(deviation_interval(1.0, 0.99 * e, 0.95).hi, 1.25);
  // A narrower interval needs more degrees of freedom.
  RecordLengthRule tight;
  tight.half_width = 0.1;
  EXPECT_GT(required_edf(tight), 4.0 * e);
}

TEST(RecordLength, TheLengthFoundGivesTheEdfAndNoShorterOne) {
  const double e = required_edf();
  for (const int alpha : {0, -1, -2}) {
    for (const double tau : {1.0, 87.0, 400.0}) {
      const double rate = 10.0;
      const double t = record_length_for_edf(tau, alpha, rate, e);
      const auto m = static_cast<std::size_t>(std::round(tau * rate));
      const auto n = static_cast<std::size_t>(std::round(t * rate)) + 1;
      EXPECT_GE(equivalent_dof(AllanKind::kAllan, alpha, m, n), e) << alpha << " " << tau;
      EXPECT_LT(equivalent_dof(AllanKind::kAllan, alpha, m, n - n / 500 - 2), e)
          << alpha << " " << tau;
      // The record is many times the tau, and noise that wanders more needs more of it.
      EXPECT_GT(t, 10.0 * tau);
    }
    EXPECT_LT(record_length_for_edf(87.0, 0, 10.0, e), record_length_for_edf(87.0, -1, 10.0, e));
    EXPECT_LT(record_length_for_edf(87.0, -1, 10.0, e), record_length_for_edf(87.0, -2, 10.0, e));
  }
}

// N = 0.01, B = 0.003, K = 2e-4 at 10 Hz: the Allan minimum near tau = sqrt(3) N / K = 87 s.
TEST(RecordLength, AShortRecordIsToldWhatItLacksAndALongOneIsEnough) {
  const double n = 0.01, b = 0.003, k = 2e-4, rate = 10.0;
  const RunNoise long_run = run_noise_of(simulate_static_rate(n, b, k, rate, 4 * 3600.0, 5), rate);
  const RunNoise short_run = run_noise_of(simulate_static_rate(n, b, k, rate, 600.0, 6), rate);
  const auto long_needs = record_length_needs(long_run);
  const auto short_needs = record_length_needs(short_run);
  ASSERT_EQ(long_needs.size(), 3u);  // one gyro channel: three figures
  ASSERT_EQ(short_needs.size(), 3u);

  // The white noise at 1 s is resolved by either record (it needs about a minute).
  for (const auto* needs : {&long_needs, &short_needs}) {
    const FigureRecordNeed& rw = need_of(*needs, "random_walk");
    EXPECT_TRUE(rw.enough);
    EXPECT_TRUE(rw.located);
    EXPECT_EQ(rw.tau_s, 1.0);
    EXPECT_LT(rw.needed_s, 600.0);
  }

  // 4 h: the minimum is located where the model puts it, and the record covers it.
  const FigureRecordNeed& bi = need_of(long_needs, "bias_instability");
  EXPECT_TRUE(bi.located);
  EXPECT_GT(bi.tau_s, 20.0);
  EXPECT_LT(bi.tau_s, 400.0);
  EXPECT_EQ(bi.alpha, -1);
  EXPECT_TRUE(bi.enough) << bi.needed_s;
  EXPECT_GT(bi.needed_s, 600.0);  // more than the short record has
  EXPECT_EQ(bi.record_length_s, long_run.duration_s);
  // The rate random walk is read past the minimum and needs a longer record.
  const FigureRecordNeed& rrw = need_of(long_needs, "rate_random_walk");
  EXPECT_DOUBLE_EQ(rrw.tau_s, 4.0 * bi.tau_s);
  EXPECT_GT(rrw.needed_s, bi.needed_s);

  // 10 min: the bias instability is not enough; either its minimum is not reached (the curve
  // still falls at the longest well-determined tau, a lower bound) or the record is shorter
  // than its tau needs.
  const FigureRecordNeed& sbi = need_of(short_needs, "bias_instability");
  EXPECT_FALSE(sbi.enough);
  EXPECT_GT(sbi.needed_s, short_run.duration_s);
  EXPECT_FALSE(need_of(short_needs, "rate_random_walk").enough);
}

TEST(RecordLength, LengthsReadAsPeopleSayThem) {
  EXPECT_EQ(format_record_length(12.0), "12 s");
  EXPECT_EQ(format_record_length(41 * 60.0), "41 min");
  EXPECT_EQ(format_record_length(3 * 3600.0), "3.0 h");
  EXPECT_EQ(format_record_length(3 * 86400.0), "3.0 d");
}

}  // namespace
}  // namespace calstand::solver

// The streamed deviations (solver::DeviationStream) against the in-memory estimators they
// replace for long records: allan(), wavelet_moments() and identify_noise_model(), on records
// simulated with exact recursions (composite_records.hpp).
#include "noise/deviation_stream.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "composite_records.hpp"
#include "core/error.hpp"
#include "noise/allan.hpp"
#include "noise/composite_noise.hpp"
#include "noise/wavelet_moments.hpp"

namespace calstand::solver {
namespace {

constexpr double kStreamFs = testing::kCompositeRateHz;  // Hz

// White + Gauss-Markov + rate random walk at the levels of a tactical gyro [deg/s]: every
// power law from white FM to random-walk FM across the octaves.
std::vector<double> stream_record(std::size_t n, unsigned seed, double bias = 0.0) {
  using K = NoiseKind;
  std::vector<double> y = testing::simulate_composite(
      {{K::kWhite, 0.005}, {K::kGaussMarkov, 0.004, 2.0}, {K::kRandomWalk, 5e-4}}, n, seed);
  for (double& v : y) v += bias;
  return y;
}

DeviationStream streamed(const std::vector<double>& y, std::size_t block, AllanKind kind,
                         std::size_t exact_max_m = DeviationStream::kExactMaxM) {
  DeviationStream s({kind}, exact_max_m);
  for (std::size_t i = 0; i < y.size(); i += block) {
    s.push(std::span<const double>(y).subspan(i, std::min(block, y.size() - i)));
  }
  return s;
}

AllanOptions stream_options(AllanKind kind) {
  AllanOptions o;
  o.kind = kind;
  return o;
}

const AllanKind kStreamedKinds[] = {AllanKind::kAllan, AllanKind::kHadamard, AllanKind::kModified};

// Below the exact budget every start sample is used: the numbers of allan() to rounding, and
// the same noise types, EDFs and intervals.
TEST(DeviationStream, BelowTheBudgetEqualsAllan) {
  // 60,000 samples: m <= 30,000 < 2^15, and fewer than the 65,536 whose mean is removed.
  // 300,000 with a budget of 2^18: the mean of the first 65,536 samples, many buffer shifts.
  struct Case {
    std::size_t n, exact_max_m, block;
  };
  for (const Case c : {Case{60000, DeviationStream::kExactMaxM, 4099},
                       Case{300000, std::size_t{1} << 18U, 65537}}) {
    const std::vector<double> y = stream_record(c.n, 11u);
    for (const AllanKind kind : kStreamedKinds) {
      SCOPED_TRACE(std::string(to_string(kind)) + " n " + std::to_string(c.n));
      const AllanResult want = allan(y, kStreamFs, stream_options(kind));
      DeviationStream s = streamed(y, c.block, kind, c.exact_max_m);
      const AllanResult got = s.result(kStreamFs, stream_options(kind));
      EXPECT_EQ(got.samples, want.samples);
      ASSERT_EQ(got.points.size(), want.points.size());
      for (std::size_t k = 0; k < want.points.size(); ++k) {
        const AllanPoint& g = got.points[k];
        const AllanPoint& w = want.points[k];
        EXPECT_EQ(g.m, w.m);
        EXPECT_EQ(g.terms, w.terms);
        EXPECT_NEAR(g.deviation / w.deviation, 1.0, 1e-12) << "m " << w.m;
        EXPECT_EQ(g.alpha, w.alpha) << "m " << w.m;
        EXPECT_NEAR(g.edf / w.edf, 1.0, 1e-9) << "m " << w.m;
        EXPECT_NEAR(g.hi / w.hi, 1.0, 1e-9) << "m " << w.m;
      }
    }
  }
}

// Above the budget the strided estimator must agree with the exact one on the same record to
// a small fraction of the exact estimator's own standard error, sigma(s^2)/s^2 = sqrt(2/edf):
// D / m = 1 / exact_max_m. A budget of 2^8 (D / m = 1/256, far coarser than the default's
// 1/32768) on 2^21 samples strides m = 512 ... 2^20.
TEST(DeviationStream, StridedAgreesWithTheExactEstimator) {
  const std::vector<double> y = stream_record(std::size_t{1} << 21U, 23u);
  for (const AllanKind kind : kStreamedKinds) {
    SCOPED_TRACE(std::string(to_string(kind)));
    const AllanResult exact = allan(y, kStreamFs, stream_options(kind));
    DeviationStream s = streamed(y, 100003, kind, 256);
    const AllanResult strided = s.result(kStreamFs, stream_options(kind));
    ASSERT_EQ(strided.points.size(), exact.points.size());
    double worst = 0.0;
    for (std::size_t k = 0; k < exact.points.size(); ++k) {
      const AllanPoint& e = exact.points[k];
      const AllanPoint& g = strided.points[k];
      const double rel = g.deviation * g.deviation / (e.deviation * e.deviation) - 1.0;
      const double se = std::sqrt(2.0 / e.edf);  // the exact estimator's relative std error
      if (e.m <= 256) {
        EXPECT_NEAR(rel, 0.0, 1e-12) << "m " << e.m;
        continue;
      }
      if (e.terms > 1) {
        EXPECT_LT(g.terms, e.terms) << "m " << e.m;  // strided indeed
      }
      EXPECT_LT(std::abs(rel), 0.1 * se) << "m " << e.m << " edf " << e.edf;
      worst = std::max(worst, std::abs(rel) / se);
    }
    std::printf("%s: strided vs exact, worst |difference| / standard error = %.3g\n",
                std::string(to_string(kind)).c_str(), worst);
  }
}

// A large constant bias (1e3 deg/s on 5e-3 deg/s/sqrt(Hz) noise, a random walk moving the
// mean after the first block): the removed first-block mean and the anchored phase keep every
// difference as exact as allan()'s with its whole-record mean.
TEST(DeviationStream, LargeBiasMatchesAllan) {
  const std::vector<double> y = stream_record((std::size_t{1} << 19U) + 12345, 5u, 1e3);
  for (const AllanKind kind : kStreamedKinds) {
    SCOPED_TRACE(std::string(to_string(kind)));
    const AllanResult want = allan(y, kStreamFs, stream_options(kind));
    DeviationStream s = streamed(y, 65536, kind, std::size_t{1} << 18U);
    const AllanResult got = s.result(kStreamFs, stream_options(kind));
    ASSERT_EQ(got.points.size(), want.points.size());
    double worst = 0.0;
    for (std::size_t k = 0; k < want.points.size(); ++k) {
      const double rel = got.points[k].deviation / want.points[k].deviation - 1.0;
      EXPECT_NEAR(rel, 0.0, 1e-11) << "m " << want.points[k].m;
      worst = std::max(worst, std::abs(rel));
    }
    std::printf("%s with a 1e3 bias: worst relative difference from allan() %.2g\n",
                std::string(to_string(kind)).c_str(), worst);
  }
}

// How the record is split into blocks does not change a bit of the result (strided levels
// included: a budget of 2^6), noise types and EDFs included.
TEST(DeviationStream, BlockSizesGiveIdenticalResults) {
  const std::vector<double> y = stream_record(150001, 3u);
  DeviationStream whole({AllanKind::kAllan, AllanKind::kHadamard, AllanKind::kModified}, 64);
  whole.push(y);
  for (const std::size_t block : {std::size_t{1}, std::size_t{7}, std::size_t{65537}}) {
    DeviationStream s({AllanKind::kAllan, AllanKind::kHadamard, AllanKind::kModified}, 64);
    for (std::size_t i = 0; i < y.size(); i += block) {
      s.push(std::span<const double>(y).subspan(i, std::min(block, y.size() - i)));
    }
    for (const AllanKind kind : kStreamedKinds) {
      const AllanResult a = whole.result(kStreamFs, stream_options(kind));
      const AllanResult b = s.result(kStreamFs, stream_options(kind));
      ASSERT_EQ(a.points.size(), b.points.size());
      for (std::size_t k = 0; k < a.points.size(); ++k) {
        EXPECT_EQ(a.points[k].deviation, b.points[k].deviation)
            << to_string(kind) << " block " << block << " m " << a.points[k].m;
        EXPECT_EQ(a.points[k].terms, b.points[k].terms);
        EXPECT_EQ(a.points[k].alpha, b.points[k].alpha);
        EXPECT_EQ(a.points[k].edf, b.points[k].edf);
      }
    }
  }
}

TEST(DeviationStream, WaveletMomentsEqualTheInMemoryOnes) {
  const std::vector<double> y = stream_record(60000, 7u);
  const WaveletMoments want = wavelet_moments(y, kStreamFs);
  DeviationStream s = streamed(y, 1000, AllanKind::kAllan);
  const WaveletMoments got = s.moments(kStreamFs);
  EXPECT_EQ(got.samples, want.samples);
  ASSERT_EQ(got.m, want.m);
  for (std::size_t j = 0; j < want.m.size(); ++j) {
    EXPECT_NEAR(got.variance[j] / want.variance[j], 1.0, 1e-12) << "m " << want.m[j];
    EXPECT_EQ(got.dof[j], want.dof[j]);
  }
}

// The GMWM needs only the moments: a streamed record identifies the same model.
TEST(DeviationStream, NoiseIdFromTheStreamEqualsTheInMemoryOne) {
  const std::vector<double> y = stream_record(60000, 19u);
  NoiseIdOptions options;
  options.min_tau_s = 0.02;
  const NoiseModel want = identify_noise_model(y, kStreamFs, options);
  DeviationStream s = streamed(y, 4096, AllanKind::kAllan);
  const NoiseModel got = identify_noise_model(s.moments(kStreamFs), options);
  EXPECT_EQ(got.samples, want.samples);
  EXPECT_EQ(got.selected_by, want.selected_by);
  ASSERT_EQ(got.terms.size(), want.terms.size());
  for (std::size_t i = 0; i < want.terms.size(); ++i) {
    EXPECT_EQ(got.terms[i].kind, want.terms[i].kind);
    EXPECT_NEAR(got.terms[i].value / want.terms[i].value, 1.0, 1e-6);
    EXPECT_NEAR(got.terms[i].value_hi / want.terms[i].value_hi, 1.0, 1e-6);
    if (want.terms[i].kind == NoiseKind::kGaussMarkov) {
      EXPECT_NEAR(got.terms[i].tau_s / want.terms[i].tau_s, 1.0, 1e-6);
    }
  }
}

TEST(DeviationStream, BadInput) {
  EXPECT_THROW(DeviationStream({}), core::InputError);
  EXPECT_THROW(DeviationStream({AllanKind::kHadamardNonOverlapping}), core::InputError);
  EXPECT_THROW(DeviationStream({AllanKind::kAllan}, 100), core::InputError);
  DeviationStream s({AllanKind::kAllan});
  std::vector<double> y(1000, 0.5);
  s.push(y);
  y[17] = std::numeric_limits<double>::quiet_NaN();
  try {
    s.push(y);
    FAIL() << "a NaN was accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sample 1017 is not finite"), std::string::npos)
        << e.what();
  }
  DeviationStream t({AllanKind::kAllan});
  t.push(stream_record(1000, 1u));
  AllanOptions dense;
  dense.taus = TauSet::parse("dense");
  EXPECT_THROW(t.result(kStreamFs, dense), core::InputError);
  EXPECT_THROW(t.result(kStreamFs, stream_options(AllanKind::kModified)), core::InputError);
  EXPECT_THROW(t.result(0.0, {}), core::InputError);
  DeviationStream one({AllanKind::kAllan});
  one.push(std::vector<double>{1.0});
  EXPECT_THROW(one.result(kStreamFs, {}), core::InputError);
}

}  // namespace
}  // namespace calstand::solver

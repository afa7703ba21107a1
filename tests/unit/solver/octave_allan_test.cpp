// The white noise floor read from the Allan curve inside static steps (octave_allan.hpp): the
// streamed octave sums against a direct computation, and the white part recovered where the
// bias wander dominates every single block length the old batch-means floor could use.
#include "solver/octave_allan.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sim/noise.hpp"

namespace calstand::solver {
namespace {

constexpr double kRateHz = 50.0;
constexpr std::int64_t kStepSamples = 3000;  // 60 s at 50 Hz, the campaigns' static step
constexpr int kSteps = 72;

/// Non-overlapping Allan variance of `x` at blocks of `m` samples, straight from its definition.
double direct_allan(const std::vector<double>& x, std::size_t m, std::int64_t* differences) {
  std::vector<double> means;
  for (std::size_t i = 0; i + m <= x.size(); i += m) {
    double sum = 0.0;
    for (std::size_t k = i; k < i + m; ++k) sum += x[k];
    means.push_back(sum / static_cast<double>(m));
  }
  double half_squares = 0.0;
  for (std::size_t b = 0; b + 1 < means.size(); ++b) {
    half_squares += 0.5 * (means[b + 1] - means[b]) * (means[b + 1] - means[b]);
  }
  *differences = static_cast<std::int64_t>(means.size()) - 1;
  return half_squares;
}

/// `kSteps` steps of `kStepSamples` from `draw` on channel 0 (the other channels white at 1),
/// their octave sums pooled as measure_noise_floor pools them.
template <class Draw>
std::vector<OctaveAllan> pooled_steps(Draw&& draw) {
  std::vector<OctaveAllan> pooled;
  sim::NormalSource other(99);
  for (int s = 0; s < kSteps; ++s) {
    OctaveAllanSums sums(octaves_for(kStepSamples));
    for (std::int64_t i = 0; i < kStepSamples; ++i) {
      Vector6d v;
      v << draw(), other.next(), other.next(), other.next(), other.next(), other.next();
      sums.add(v);
    }
    const std::vector<OctaveAllan> step = sums.result();
    pooled.resize(step.size());
    for (std::size_t j = 0; j < step.size(); ++j) {
      pooled[j].half_squared_differences += step[j].half_squared_differences;
      pooled[j].differences += step[j].differences;
    }
  }
  return pooled;
}

/// The old floor: tau AVAR at a tenth of a step (the batch means' block), per sample.
double batch_means_figure(const std::vector<OctaveAllan>& pooled) {
  const OctaveAllan& last = pooled.back();
  return std::ldexp(1.0, static_cast<int>(pooled.size()) - 1) * last.half_squared_differences[0] /
         static_cast<double>(last.differences);
}

TEST(OctaveAllan, StreamedSumsEqualTheDefinitionAtEveryOctave) {
  sim::NormalSource n(7);
  std::vector<double> x;
  OctaveAllanSums sums(octaves_for(1000));
  for (int i = 0; i < 1000; ++i) {
    // White noise on a slow ramp, so that blocks of different lengths differ.
    x.push_back(n.next() + 1e-3 * i);
    sums.add(Vector6d::Constant(x.back()));
  }
  const std::vector<OctaveAllan> result = sums.result();
  ASSERT_EQ(result.size(), 7u);  // blocks of 1 to 64 samples: at least 10 in 1000
  for (std::size_t j = 0; j < result.size(); ++j) {
    std::int64_t differences = 0;
    const double expected = direct_allan(x, std::size_t{1} << j, &differences);
    EXPECT_EQ(result[j].differences, differences) << "octave " << j;
    EXPECT_NEAR(result[j].half_squared_differences[0], expected, 1e-9 * expected) << "octave " << j;
  }
}

TEST(OctaveAllan, WhiteNoiseAloneIsItsOwnFloor) {
  sim::WhiteNoise white(0.1, kRateHz, 11);
  const auto pooled = pooled_steps([&] { return white.next(); });
  const auto q = white_variance_from_octaves(pooled, kStepSamples / 10);
  ASSERT_TRUE(q);
  const double truth = white.sigma() * white.sigma();
  EXPECT_NEAR((*q)[0], truth, 0.03 * truth);
  EXPECT_NEAR((*q)[1], 1.0, 0.03);
}

// An ADIS16488-class accelerometer: 46 ug/sqrt(Hz) under a 0.1 mg flicker floor. At a tenth of a
// 60 s step the flicker is 15 times the white noise, and the batch means' figure is many times
// the white variance; the curve's white part is the sheet's to within the flicker band's foot.
TEST(OctaveAllan, FlickerAboveTheWhiteNoiseStaysOutOfTheFloor) {
  const double g = 9.80665;
  sim::WhiteNoise white(46e-6 * g, kRateHz, 21);
  sim::BiasInstability flicker(0.1e-3 * g / sim::kFlickerAllanFloorPerCoefficient, 1.0 / kRateHz,
                               22);
  const auto pooled = pooled_steps([&] { return white.next() + flicker.next(); });
  const double truth = white.sigma() * white.sigma();
  EXPECT_GT(batch_means_figure(pooled), 10.0 * truth);
  const auto q = white_variance_from_octaves(pooled, kStepSamples / 10);
  ASSERT_TRUE(q);
  EXPECT_GT((*q)[0], 0.7 * truth);
  EXPECT_LT((*q)[0], 1.15 * truth);
}

// A MEMS accelerometer whose Gauss-Markov bias (700 ug, 300 s) moves a 6 s block more than its
// white noise does: below its correlation time it rises like a random walk (c2).
TEST(OctaveAllan, AGaussMarkovBiasStaysOutOfTheFloor) {
  const double g = 9.80665;
  sim::WhiteNoise white(100e-6 * g, kRateHz, 31);
  sim::GaussMarkov bias(700e-6 * g, 300.0, 1.0 / kRateHz, 32);
  const auto pooled = pooled_steps([&] { return white.next() + bias.next(); });
  const double truth = white.sigma() * white.sigma();
  EXPECT_GT(batch_means_figure(pooled), 3.0 * truth);
  const auto q = white_variance_from_octaves(pooled, kStepSamples / 10);
  ASSERT_TRUE(q);
  EXPECT_NEAR((*q)[0], truth, 0.05 * truth);
}

// An output filter (first order, time constant 1.5 samples) lowers the shortest blocks' Allan
// variance; the white part is still the variance of a long mean, which the filter keeps.
TEST(OctaveAllan, AnOutputFilterDoesNotLowerTheFloor) {
  sim::NormalSource n(41);
  const double a = std::exp(-1.0 / 1.5);
  double state = 0.0;
  const auto pooled = pooled_steps([&] {
    state = a * state + (1.0 - a) * n.next();
    return state;
  });
  // Low-frequency variance per sample of the filtered unit white noise: ((1 - a) / (1 - a))^2 = 1.
  const auto q = white_variance_from_octaves(pooled, kStepSamples / 10);
  ASSERT_TRUE(q);
  EXPECT_NEAR((*q)[0], 1.0, 0.08);
}

TEST(OctaveAllan, TooFewOctavesLeaveTheFloorToTheBatchMeans) {
  sim::NormalSource n(51);
  OctaveAllanSums sums(octaves_for(60));  // blocks of 1, 2 and 4 samples: one usable octave
  for (int i = 0; i < 60; ++i) sums.add(Vector6d::Constant(n.next()));
  EXPECT_FALSE(white_variance_from_octaves(sums.result(), 6));
}

}  // namespace
}  // namespace calstand::solver

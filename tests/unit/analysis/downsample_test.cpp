// The plot downsampler: at most max_points buckets, every sample inside its bucket's min..max, a
// single spike kept, the overall mean kept; on seeded random series.
#include "analysis/downsample.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

namespace calstand::analysis {
namespace {

struct Series {
  std::vector<double> t, v;
};

// White noise at `rate_hz` over `duration_s`, seeded, with one spike of `spike` at `spike_at`.
Series noisy(double rate_hz, double duration_s, unsigned seed, double spike, std::size_t spike_at) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Series s;
  const auto n = static_cast<std::size_t>(rate_hz * duration_s);
  for (std::size_t i = 0; i < n; ++i) {
    s.t.push_back(static_cast<double>(i) / rate_hz);
    s.v.push_back(i == spike_at ? spike : normal(rng));
  }
  return s;
}

TEST(Downsampler, KeepsAtMostMaxPointsBucketsAndEverySampleWithinItsBucket) {
  const Series s = noisy(1000.0, 600.0, 7, 0.0, 0);
  for (std::size_t max_points : {2u, 3u, 100u, 2000u}) {
    Downsampler d(max_points);
    for (std::size_t i = 0; i < s.t.size(); ++i) d.add(s.t[i], s.v[i]);
    const DownsampledSeries r = d.result();
    EXPECT_LE(r.t_s.size(), max_points);
    // Halving the width once more would exceed max_points: the buckets are as fine as allowed.
    EXPECT_GT(r.t_s.size(), max_points / 2) << max_points;
    EXPECT_EQ(r.samples, static_cast<std::int64_t>(s.t.size()));
    const double w = d.bucket_s();
    for (std::size_t i = 0; i < s.t.size(); i += 997) {
      // The bucket of sample i: the one whose floor(t / w) matches.
      const double key = std::floor(s.t[i] / w);
      const auto it = std::find_if(r.t_s.begin(), r.t_s.end(),
                                   [&](double t) { return std::floor(t / w) == key; });
      ASSERT_NE(it, r.t_s.end());
      const auto b = static_cast<std::size_t>(it - r.t_s.begin());
      EXPECT_LE(r.min[b], s.v[i]);
      EXPECT_GE(r.max[b], s.v[i]);
      EXPECT_LE(r.min[b], r.mean[b]);
      EXPECT_GE(r.max[b], r.mean[b]);
    }
    EXPECT_TRUE(std::is_sorted(r.t_s.begin(), r.t_s.end()));
  }
}

TEST(Downsampler, AOneSampleSpikeSurvivesInTheMaximum) {
  const Series s = noisy(1000.0, 3600.0, 11, 50.0, 1'234'567);
  Downsampler d(500);
  for (std::size_t i = 0; i < s.t.size(); ++i) d.add(s.t[i], s.v[i]);
  const DownsampledSeries r = d.result();
  EXPECT_DOUBLE_EQ(*std::max_element(r.max.begin(), r.max.end()), 50.0);
  // Only the spike's bucket shows it: noise of unit sigma stays below 10.
  EXPECT_EQ(std::count_if(r.max.begin(), r.max.end(), [](double m) { return m > 10.0; }), 1);
}

TEST(Downsampler, TheMeansWeightedByBucketReproduceTheSeriesMean) {
  const Series s = noisy(200.0, 100.0, 3, 0.0, 0);
  Downsampler d(64);
  for (std::size_t i = 0; i < s.t.size(); ++i) d.add(s.t[i], s.v[i] + 5.0);
  const DownsampledSeries r = d.result();
  const double mean =
      std::accumulate(s.v.begin(), s.v.end(), 0.0) / static_cast<double>(s.v.size()) + 5.0;
  // Equal-width buckets of a uniformly sampled series hold equal counts but the last.
  const double bucket_mean = std::accumulate(r.mean.begin(), r.mean.end() - 1, 0.0) /
                             static_cast<double>(r.mean.size() - 1);
  EXPECT_NEAR(bucket_mean, mean, 0.05);
}

TEST(Downsampler, AcceptsSamplesOutOfOrderAndBeforeZero) {
  Downsampler d(10);
  for (int i = 999; i >= -1000; --i) d.add(static_cast<double>(i) * 0.01, static_cast<double>(i));
  const DownsampledSeries r = d.result();
  EXPECT_LE(r.t_s.size(), 10u);
  EXPECT_EQ(r.samples, 2000);
  EXPECT_DOUBLE_EQ(r.min.front(), -1000.0);
  EXPECT_DOUBLE_EQ(r.max.back(), 999.0);
}

TEST(Downsampler, CountsButSkipsNonFiniteValues) {
  Downsampler d(10);
  d.add(0.0, 1.0);
  d.add(0.001, std::nan(""));
  const DownsampledSeries r = d.result();
  EXPECT_EQ(r.samples, 2);
  ASSERT_EQ(r.mean.size(), 1u);
  EXPECT_DOUBLE_EQ(r.mean[0], 1.0);
}

TEST(Downsampler, RefusesFewerThanTwoPoints) {
  EXPECT_THROW(Downsampler(1), std::invalid_argument);
}

}  // namespace
}  // namespace calstand::analysis

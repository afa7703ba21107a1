#pragma once
// Reducing a long time series to at most a few thousand points for a plot, keeping per bucket
// the minimum and maximum (a one-sample spike survives) and the mean.

#include <cstddef>
#include <cstdint>
#include <map>
#include <vector>

namespace calstand::analysis {

/// The buckets of a downsampled series, in time order; empty buckets are left out.
struct DownsampledSeries {
  std::vector<double> t_s;   ///< mean time of the samples in each bucket [s]
  std::vector<double> min;   ///< smallest value in each bucket
  std::vector<double> max;   ///< largest value in each bucket
  std::vector<double> mean;  ///< mean value in each bucket
  std::int64_t samples = 0;  ///< samples added (all buckets)
};

/// Streams samples into equal-width time buckets without knowing the series' length first:
/// buckets start kInitialBucketS wide and double (neighbours merged) whenever the span of
/// buckets in use would exceed `max_points`, so memory stays O(max_points) and the result
/// holds at most `max_points` buckets, each at least as fine as the series needs. Samples may
/// arrive in any order (fastest in time order). Not thread safe.
class Downsampler {
 public:
  /// The first bucket width [s]: finer than any IMU's sample period in use.
  static constexpr double kInitialBucketS = 1e-3;

  /// `max_points` >= 2.
  explicit Downsampler(std::size_t max_points);

  /// Adds the sample `value` at time `t_s`; non-finite values are counted but not bucketed.
  void add(double t_s, double value);

  /// The bucket width now [s].
  double bucket_s() const { return width_s_; }

  DownsampledSeries result() const;

 private:
  struct Bucket {
    double t_sum = 0.0;
    double sum = 0.0;
    double min = 0.0;
    double max = 0.0;
    std::int64_t count = 0;
  };
  void widen();
  std::size_t max_points_;
  double width_s_ = kInitialBucketS;
  std::map<std::int64_t, Bucket> buckets_;  ///< by floor(t / width)
  std::map<std::int64_t, Bucket>::iterator last_ = buckets_.end();
  std::int64_t samples_ = 0;
};

}  // namespace calstand::analysis

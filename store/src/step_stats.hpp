#pragma once
// Private: running mean and spread of a step attempt's samples (table step_means).

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/imu_sample.hpp"

namespace calstand::store {

/// Count, time span, mean and sample standard deviation of the seven channels (gyro xyz
/// [deg/s], accel xyz [m/s^2], temperature [degC]) of a stream of samples, in full precision.
///
/// Sums are of differences from the first sample (a shifted-data algorithm): as cheap as plain
/// sums and free of the cancellation that plain sums of squares suffer at 1 g with micro-g noise.
class StepStats {
 public:
  static constexpr int kChannels = 7;

  void add(const core::ImuSample& s) {
    const std::array<double, kChannels> v = channels(s);
    if (count_ == 0) {
      shift_ = v;
      first_time_s_ = s.receive_time_s;
    }
    for (int c = 0; c < kChannels; ++c) {
      const double d = v[c] - shift_[c];
      sum_[c] += d;
      sum_sq_[c] += d * d;
    }
    last_time_s_ = s.receive_time_s;
    ++count_;
  }

  std::uint64_t count() const { return count_; }
  double first_time_s() const { return first_time_s_; }
  double last_time_s() const { return last_time_s_; }
  double mean(int c) const { return shift_[c] + sum_[c] / static_cast<double>(count_); }
  /// Sample standard deviation (n - 1); NaN for fewer than two samples.
  double stddev(int c) const {
    if (count_ < 2) return std::numeric_limits<double>::quiet_NaN();
    const double n = static_cast<double>(count_);
    const double var = (sum_sq_[c] - sum_[c] * sum_[c] / n) / (n - 1.0);
    return std::sqrt(var > 0.0 ? var : 0.0);
  }

 private:
  static std::array<double, kChannels> channels(const core::ImuSample& s) {
    return {s.gyro_dps.x(),   s.gyro_dps.y(),   s.gyro_dps.z(), s.accel_mps2.x(),
            s.accel_mps2.y(), s.accel_mps2.z(), s.temperature_c};
  }

  std::uint64_t count_ = 0;
  double first_time_s_ = 0.0;
  double last_time_s_ = 0.0;
  std::array<double, kChannels> shift_{};
  std::array<double, kChannels> sum_{};
  std::array<double, kChannels> sum_sq_{};
};

}  // namespace calstand::store

#include "analysis/downsample.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace calstand::analysis {

Downsampler::Downsampler(std::size_t max_points) : max_points_(max_points) {
  if (max_points < 2) throw std::invalid_argument("Downsampler: max_points must be >= 2");
}

void Downsampler::add(double t_s, double value) {
  ++samples_;
  if (!std::isfinite(value) || !std::isfinite(t_s)) return;
  auto key = static_cast<std::int64_t>(std::floor(t_s / width_s_));
  if (last_ == buckets_.end() || last_->first != key) {
    // Widen first, so that the new bucket never makes the span exceed max_points.
    while (!buckets_.empty() &&
           std::max(key, buckets_.rbegin()->first) - std::min(key, buckets_.begin()->first) + 1 >
               static_cast<std::int64_t>(max_points_)) {
      widen();
      key = static_cast<std::int64_t>(std::floor(t_s / width_s_));
    }
    last_ = buckets_.try_emplace(key).first;
  }
  Bucket& b = last_->second;
  if (b.count == 0) {
    b.min = value;
    b.max = value;
  } else {
    b.min = std::min(b.min, value);
    b.max = std::max(b.max, value);
  }
  b.t_sum += t_s;
  b.sum += value;
  ++b.count;
}

void Downsampler::widen() {
  std::map<std::int64_t, Bucket> merged;
  for (const auto& [key, b] : buckets_) {
    // floor(key / 2), also for negative keys (an arithmetic shift).
    Bucket& m = merged[key >> 1];
    if (m.count == 0) {
      m = b;
      continue;
    }
    m.min = std::min(m.min, b.min);
    m.max = std::max(m.max, b.max);
    m.t_sum += b.t_sum;
    m.sum += b.sum;
    m.count += b.count;
  }
  buckets_ = std::move(merged);
  last_ = buckets_.end();
  width_s_ *= 2.0;
}

DownsampledSeries Downsampler::result() const {
  DownsampledSeries out;
  out.samples = samples_;
  for (const auto& [key, b] : buckets_) {
    const double n = static_cast<double>(b.count);
    out.t_s.push_back(b.t_sum / n);
    out.min.push_back(b.min);
    out.max.push_back(b.max);
    out.mean.push_back(b.sum / n);
  }
  return out;
}

}  // namespace calstand::analysis

// Power-law noise identification by the lag-1 autocorrelation of the decimated, differenced
// phase (Riley and Greenhall, EFTF 2004), the method Stable32 and SP 1065 use to pick the EDF
// formula and the bias correction at each tau; in memory, and accumulated as a record streams.
#include "noise/noise_identification.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace calstand::solver {
namespace {

// Lag-1 autocorrelation of z about its mean; NaN for a constant series.
double lag1_autocorrelation(const std::vector<double>& z) {
  double mean = 0.0;
  for (double v : z) mean += v;
  mean /= static_cast<double>(z.size());
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < z.size(); ++i) {
    const double d = z[i] - mean;
    den += d * d;
    if (i + 1 < z.size()) num += d * (z[i + 1] - mean);
  }
  return den > 0.0 ? num / den : std::nan("");
}

// The noise type from the lag-1 autocorrelations of the series differenced d = 0, 1, ... times:
// r1_at(d), asked for in increasing d, NaN when it cannot be taken.
template <typename R1At>
std::optional<Lag1NoiseId> identify_from(R1At&& r1_at, std::size_t points, int dmax,
                                         int min_alpha) {
  Lag1NoiseId out;
  out.points = points;
  for (int d = 0;; ++d) {
    const double r1 = r1_at(d);
    if (!std::isfinite(r1)) return std::nullopt;
    const double delta = r1 / (1.0 + r1);
    // White noise of the differenced series has r1 = 0 (delta 0); each difference of a
    // power law moves its exponent by 2 and its r1 towards -1/2 (delta -1): stop when the
    // series is stationary (delta < 1/4), as the paper prescribes.
    if (delta < 0.25 || d >= dmax) {
      const double p = -2.0 * (delta + d);
      out.alpha_estimate = p + 2.0;
      out.differences = d;
      out.alpha = std::clamp(static_cast<int>(std::lround(out.alpha_estimate)), min_alpha, 2);
      return out;
    }
  }
}

}  // namespace

std::optional<Lag1NoiseId> identify_noise_lag1(std::span<const double> x, std::size_t m, int dmax,
                                               int min_alpha) {
  if (m == 0 || x.empty()) return std::nullopt;
  std::vector<double> z;
  z.reserve(x.size() / m + 1);
  for (std::size_t i = 0; i < x.size(); i += m) z.push_back(x[i]);
  if (z.size() < kLag1MinPoints) return std::nullopt;
  const std::size_t points = z.size();
  const auto r1_at = [&z](int d) {
    if (d > 0) {
      for (std::size_t i = 0; i + 1 < z.size(); ++i) z[i] = z[i + 1] - z[i];
      z.pop_back();
      if (z.size() < 2) return std::nan("");
    }
    return lag1_autocorrelation(z);
  };
  return identify_from(r1_at, points, dmax, min_alpha);
}

std::size_t lag1_longest_octave_factor(std::size_t samples) {
  // floor(samples / m) + 1 >= kLag1MinPoints  <=>  m <= floor(samples / (kLag1MinPoints - 1))
  const std::size_t longest = samples / (kLag1MinPoints - 1);
  return longest == 0 ? 0 : std::bit_floor(longest);
}

Lag1Accumulator::Lag1Accumulator(int dmax) : dmax_(dmax) {
  if (dmax < 0 || dmax > kMaxDifferences) {
    throw std::invalid_argument("Lag1Accumulator: dmax must be in [0, 3]");
  }
}

void Lag1Accumulator::push(double z) {
  // The newest value of each difference order, as identify_noise_lag1 forms them (the newer
  // value minus the older), each order starting one point after the one below.
  const std::size_t lane = points_ & 1U;
  double y = z;
  for (int d = 0; d <= dmax_; ++d) {
    Sums& s = sums_[static_cast<std::size_t>(d)];
    const bool has_previous = s.n > 0.0;
    const double previous = s.last;
    if (has_previous) {
      s.products[lane] += previous * y;
    } else {
      s.first = y;
    }
    s.n += 1.0;
    s.sum[lane] += y;
    s.squares[lane] += y * y;
    s.last = y;
    if (!has_previous) break;
    y -= previous;
  }
  weighted_[lane] += static_cast<double>(points_) * z;
  ++points_;
}

namespace {

// Two doubles in one register (GCC and Clang vector extension): the even and the odd lane.
using Pair = double __attribute__((vector_size(16)));

// One difference order's running sums in locals (registers), and the step push(double) takes
// for a pair of new values (y[0] at an even index, y[1] the next): their products with the value
// before each, their sums and squares; returns the next order's pair.
struct Run {
  Pair sum, squares, products;
  double last;
};

inline Pair step(Run& r, Pair y) {
  const Pair before = {r.last, y[0]};
  r.products += before * y;
  r.sum += y;
  r.squares += y * y;
  r.last = y[1];
  return y - before;
}

}  // namespace

template <int D>
void Lag1Accumulator::push_each(const double* z, std::size_t n, std::size_t stride, double offset) {
  // push(double) on pairs of points with every order past its first value; points_ is even.
  const auto load = [this](int d) {
    const Sums& s = sums_[static_cast<std::size_t>(d)];
    return Run{Pair{s.sum[0], s.sum[1]}, Pair{s.squares[0], s.squares[1]},
               Pair{s.products[0], s.products[1]}, s.last};
  };
  const auto store = [this, n](int d, const Run& r) {
    Sums& s = sums_[static_cast<std::size_t>(d)];
    s.n += static_cast<double>(n);
    s.sum = {r.sum[0], r.sum[1]};
    s.squares = {r.squares[0], r.squares[1]};
    s.products = {r.products[0], r.products[1]};
    s.last = r.last;
  };
  Run r0 = load(0), r1 = D >= 1 ? load(1) : Run{}, r2 = D >= 2 ? load(2) : Run{},
      r3 = D >= 3 ? load(3) : Run{};
  Pair weighted = {weighted_[0], weighted_[1]};
  Pair k = {static_cast<double>(points_), static_cast<double>(points_ + 1)};
  const Pair two = {2.0, 2.0};
  for (std::size_t i = 0; i + 1 < n; i += 2) {
    const Pair y = Pair{z[i * stride], z[(i + 1) * stride]} + offset;
    weighted += k * y;
    k += two;
    const Pair y1 = step(r0, y);
    if constexpr (D >= 1) {
      const Pair y2 = step(r1, y1);
      if constexpr (D >= 2) {
        const Pair y3 = step(r2, y2);
        if constexpr (D >= 3) step(r3, y3);
      }
    }
  }
  store(0, r0);
  if constexpr (D >= 1) store(1, r1);
  if constexpr (D >= 2) store(2, r2);
  if constexpr (D >= 3) store(3, r3);
  weighted_ = {weighted[0], weighted[1]};
  points_ += n;
}

void Lag1Accumulator::push(const double* z, std::size_t n, std::size_t stride, double offset) {
  std::size_t i = 0;
  // One at a time until every order has begun (order d begins at point d) and the next point
  // is an even one; then in pairs; the odd one left, if any, alone.
  for (; i < n && (points_ <= static_cast<std::size_t>(dmax_) || points_ % 2 != 0); ++i) {
    push(z[i * stride] + offset);
  }
  const std::size_t pairs = (n - i) / 2;
  if (pairs > 0) {
    const double* from = z + i * stride;
    switch (dmax_) {
      case 0:
        push_each<0>(from, 2 * pairs, stride, offset);
        break;
      case 1:
        push_each<1>(from, 2 * pairs, stride, offset);
        break;
      case 2:
        push_each<2>(from, 2 * pairs, stride, offset);
        break;
      default:
        push_each<3>(from, 2 * pairs, stride, offset);
        break;
    }
    i += 2 * pairs;
  }
  if (i < n) push(z[i * stride] + offset);
}

std::optional<Lag1NoiseId> Lag1Accumulator::identify(int dmax, int min_alpha, double ramp) const {
  if (dmax > dmax_) throw std::invalid_argument("Lag1Accumulator: dmax beyond the accumulated");
  if (points_ < kLag1MinPoints) return std::nullopt;
  const auto r1_at = [&](int d) {
    const Sums& lanes = sums_[static_cast<std::size_t>(d)];
    struct {
      double n, sum, squares, products, first, last;
    } s{lanes.n,
        lanes.sum[0] + lanes.sum[1],
        lanes.squares[0] + lanes.squares[1],
        lanes.products[0] + lanes.products[1],
        lanes.first,
        lanes.last};
    const double weighted = weighted_[0] + weighted_[1];
    if (s.n < 2.0) return std::nan("");
    if (d == 0 && ramp != 0.0) {
      // The sums of u_k = z_k - ramp k from those of z_k and sum k z_k (k = 0 .. n - 1).
      const double n = s.n, b = ramp;
      const double k1 = n * (n - 1.0) / 2.0;                    // sum k
      const double k2 = (n - 1.0) * n * (2.0 * n - 1.0) / 6.0;  // sum k^2
      const double kk = (n - 2.0) * (n - 1.0) * n / 3.0;        // sum k (k + 1), k < n - 1
      s.products -= b * (2.0 * weighted - n * s.last + s.first) - b * b * kk;
      s.squares += -2.0 * b * weighted + b * b * k2;
      s.sum -= b * k1;
      s.last -= b * (n - 1.0);
    }
    // About the mean: sum (y - mean)^2 and sum over neighbours of (y_i - mean)(y_i+1 - mean).
    const double mean = s.sum / s.n;
    const double den = s.squares - s.sum * mean;
    const double num =
        s.products - mean * (2.0 * s.sum - s.first - s.last) + (s.n - 1.0) * mean * mean;
    // A constant series leaves only rounding in den.
    return den > 1e-13 * s.squares ? num / den : std::nan("");
  };
  return identify_from(r1_at, points_, dmax, min_alpha);
}

}  // namespace calstand::solver

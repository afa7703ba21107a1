// Power-law noise identification by the lag-1 autocorrelation of the decimated, differenced
// phase (Riley and Greenhall, EFTF 2004), the method Stable32 and SP 1065 use to pick the EDF
// formula and the bias correction at each tau.
#include "noise/noise_identification.hpp"

#include <algorithm>
#include <cmath>
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

}  // namespace

std::optional<Lag1NoiseId> identify_noise_lag1(std::span<const double> x, std::size_t m, int dmax,
                                               int min_alpha) {
  if (m == 0 || x.empty()) return std::nullopt;
  std::vector<double> z;
  z.reserve(x.size() / m + 1);
  for (std::size_t i = 0; i < x.size(); i += m) z.push_back(x[i]);
  if (z.size() < kLag1MinPoints) return std::nullopt;
  Lag1NoiseId out;
  out.points = z.size();
  for (int d = 0;; ++d) {
    const double r1 = lag1_autocorrelation(z);
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
    for (std::size_t i = 0; i + 1 < z.size(); ++i) z[i] = z[i + 1] - z[i];
    z.pop_back();
    if (z.size() < 2) return std::nullopt;
  }
}

}  // namespace calstand::solver

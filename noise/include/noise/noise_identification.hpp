#pragma once

#include <cstddef>
#include <optional>
#include <span>

namespace calstand::solver {

/// Dominant power-law noise of a record at one averaging factor by the lag-1 autocorrelation
/// (W. Riley and C. Greenhall, "Power law noise identification using the lag 1
/// autocorrelation", 18th EFTF, 2004; NIST SP 1065 section 5.5.5).
struct Lag1NoiseId {
  double alpha_estimate = 0.0;  ///< the unrounded exponent p + 2 (S_y ~ f^alpha)
  int alpha = 0;                ///< rounded, clamped to the estimator's range
  int differences = 0;          ///< differences taken before the autocorrelation fell below 0.25
  std::size_t points = 0;       ///< decimated phase points the autocorrelation was taken on
};

/// Minimum decimated points for the method: the paper finds it reliable from about 30.
inline constexpr std::size_t kLag1MinPoints = 30;

/// The noise type at averaging factor m of the phase `x` (N points, any unit): the phase is
/// decimated by m (every m-th point), then differenced d = 0, 1, ... times until
/// delta = r1 / (1 + r1) of the lag-1 autocorrelation r1 is below 0.25 or d = dmax
/// (2 for the Allan family, 3 for the Hadamard family); p = -2 (delta + d) is the phase
/// spectrum's exponent and alpha = p + 2. The result is rounded and clamped to
/// [min_alpha, 2]. nullopt when fewer than kLag1MinPoints decimated points remain (the
/// caller carries the last identified type forward) or the data are constant.
std::optional<Lag1NoiseId> identify_noise_lag1(std::span<const double> x, std::size_t m, int dmax,
                                               int min_alpha);

}  // namespace calstand::solver

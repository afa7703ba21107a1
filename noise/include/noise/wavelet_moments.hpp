#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace calstand::solver {

/// Haar wavelet variances of a rate record at dyadic scales: the moments the GMWM matches
/// (Guerrier, Skaloud, Stebler and Victoria-Feser, "Wavelet-variance-based estimation for
/// composite stochastic processes", JASA 108, 2013). The maximal-overlap Haar wavelet variance
/// at scale tau_j = 2^j samples is half the overlapping Allan variance at m = 2^(j-1) (Percival
/// and Guttorp 1994), so it is computed from the phase as allan() does.
struct WaveletMoments {
  double sample_rate_hz = 0.0;
  std::size_t samples = 0;
  std::vector<std::size_t> m;    ///< half-scale (Allan averaging factor) 1, 2, 4, ...
  std::vector<double> variance;  ///< Haar wavelet variance nu^2 [unit^2]
  std::vector<double> dof;       ///< its equivalent degrees of freedom (see wavelet_moments())
};

/// The Haar wavelet variances of `rate` at m = 1, 2, 4, ... up to samples / 4 (at least 4
/// scales: throws core::InputError naming the data for fewer than 32 samples, a non-finite
/// sample or a non-positive rate). The degrees of freedom are white FM's for the overlapping
/// Allan variance (SP 1065 Table 5), at least 1.
WaveletMoments wavelet_moments(std::span<const double> rate, double sample_rate_hz);

/// The moments wavelet_moments() gives from the overlapping Allan variances avar[j] at
/// m = 2^j (as many as given, up to samples / 4) of a record of `samples` samples; for a
/// streamed record (solver::DeviationStream). Does not check its input.
WaveletMoments wavelet_moments_from_allan(std::span<const double> avar, std::size_t samples,
                                          double sample_rate_hz);

}  // namespace calstand::solver

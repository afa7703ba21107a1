#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <vector>

namespace calstand::solver {

/// The covariance of the Haar wavelet variance estimates of a Gaussian record across scales,
/// the weighting the GMWM needs to be efficient (Guerrier et al., JASA 108, 2013, section 3):
///
///   Cov(nu_j, nu_k) = (2 / sqrt(M_j M_k)) int_{-1/2}^{1/2} |H_j(f)|^2 |H_k(f)|^2 S(f)^2 df
///
/// (Percival 1995's large-sample form: the wavelet coefficients are Gaussian, so the covariance
/// of their squares is twice their squared cross-covariance, summed over lags by Parseval).
/// |H_j(f)|^2 = sin^4(pi f m) / (m^2 sin^2(pi f)) is the Haar filter at half-scale m, M = N + 1
/// - 2m the number of its overlapping coefficients. The spectrum is given as that of the first
/// difference, D(f) = 4 sin^2(pi f) S(f), which is bounded for a random walk too (the Haar
/// filter differences once, so the coefficients are stationary).
///
/// `m`: the half-scales (samples, powers of 2, ascending); `samples`: N; `diff_psd(f)`: D at
/// f in (0, 1/2] cycles per sample, two-sided, in unit^2 per cycle/sample. The integral is
/// taken on a dense grid where the filters oscillate slowly against their envelope and with
/// each oscillation replaced by its mean beyond 16 periods (the envelope falls as f^-8 there).
/// Thread safe; cost about 10^5 evaluations of diff_psd for 20 scales.
Eigen::MatrixXd wavelet_variance_covariance(const std::vector<std::size_t>& m, std::size_t samples,
                                            const std::function<double(double)>& diff_psd);

}  // namespace calstand::solver

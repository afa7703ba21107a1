// Haar wavelet variances of a rate record (the moments of the GMWM), from the overlapping Allan
// variance at octave averaging factors.
#include "noise/wavelet_moments.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "noise/allan.hpp"

namespace calstand::solver {

WaveletMoments wavelet_moments(std::span<const double> rate, double sample_rate_hz) {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    throw core::InputError("rate",
                           fmt::format("must be positive and finite, got {}", sample_rate_hz));
  }
  if (rate.size() < 32) {
    throw core::InputError("data", fmt::format("noise identification needs at least 32 samples "
                                               "(4 dyadic scales), got {}",
                                               rate.size()));
  }
  const std::vector<double> x = phase_from_rate(rate);
  std::vector<double> avar;
  for (std::size_t m = 1; m <= rate.size() / 4; m *= 2) {
    avar.push_back(allan_variance_from_phase(x, m, AllanKind::kAllan));
  }
  return wavelet_moments_from_allan(avar, rate.size(), sample_rate_hz);
}

WaveletMoments wavelet_moments_from_allan(std::span<const double> avar, std::size_t samples,
                                          double sample_rate_hz) {
  WaveletMoments out;
  out.sample_rate_hz = sample_rate_hz;
  out.samples = samples;
  std::size_t m = 1;
  for (std::size_t j = 0; j < avar.size() && m <= samples / 4; ++j, m *= 2) {
    out.m.push_back(m);
    out.variance.push_back(0.5 * avar[j]);
    // White FM's EDF of the overlapping Allan variance (SP 1065 Table 5), the middle of the
    // power laws: white PM has more, random walk fewer (about N / m); Percival and Walden's
    // eta_3 = M / 2m, a lower bound, made the objective of a right model a third of its
    // expected J - p and the selection penalty too heavy.
    const double n = static_cast<double>(samples + 1);
    const double md = static_cast<double>(m);
    const double white_fm = (3.0 * (n - 1.0) / (2.0 * md) - 2.0 * (n - 2.0) / n) * 4.0 * md * md /
                            (4.0 * md * md + 5.0);
    out.dof.push_back(std::max(white_fm, 1.0));
  }
  return out;
}

}  // namespace calstand::solver

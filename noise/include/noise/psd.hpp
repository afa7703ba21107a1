#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace calstand::solver {

/// Options of welch_psd().
struct WelchOptions {
  /// Samples per segment; 0 picks the largest power of two that gives at least 8 segments
  /// (at 50 % overlap), at least 16 samples and at most 2^20.
  std::size_t segment_length = 0;
  double overlap = 0.5;  ///< fraction of a segment shared with the next, in [0, 1)

  /// Throws core::InputError naming the field for an overlap outside [0, 1) or a segment
  /// length below 4.
  void validate() const;
};

/// A one-sided power spectral density.
struct Psd {
  std::vector<double> frequency_hz;  ///< 0 .. sample_rate / 2, spacing sample_rate / length
  std::vector<double> density;       ///< [unit^2/Hz], one-sided (sums to the variance)
  std::size_t segments = 0;          ///< segments averaged
  std::size_t segment_length = 0;
  double resolution_hz = 0.0;  ///< frequency spacing [Hz]
  /// Effective noise bandwidth of one bin [Hz]: 1.5 bins for the Hann window.
  double enbw_hz = 0.0;
};

/// Welch's averaged periodogram of `data` [unit] sampled at sample_rate_hz: Hann-windowed
/// segments, each with its mean removed, FFT by FFTW, averaged, scaled to a one-sided density
/// in unit^2/Hz (white noise of variance s^2 reads 2 s^2 / fs at every frequency but DC and
/// Nyquist, which are not doubled). For a gyro in deg/s the density is in (deg/s)^2/Hz; its
/// square root at the white level is the angle random walk in deg/s/sqrt(Hz) = deg/sqrt(s)
/// after dividing by sqrt(2) (the one-sided factor).
///
/// Throws core::InputError for fewer samples than one segment (or 16 with the automatic
/// length), a non-finite sample (named), a non-positive rate or invalid options. FFTW's planner
/// is not thread safe; plans are made under a lock shared with autocorrelation().
Psd welch_psd(std::span<const double> data, double sample_rate_hz,
              const WelchOptions& options = {});

/// A sample autocorrelation.
struct Autocorrelation {
  std::vector<double> lag_s;        ///< k / sample_rate [s]
  std::vector<double> covariance;   ///< biased: (1/n) sum x_i x_{i+k}, mean removed [unit^2]
  std::vector<double> correlation;  ///< covariance / covariance[0]
};

/// The biased autocovariance and normalised autocorrelation of `data` for lags 0..max_lag
/// (clamped to n - 1), via FFT of the zero-padded, mean-removed data (O(n log n)). The biased
/// estimator (divide by n at every lag) keeps the sequence positive semi-definite; it shrinks
/// lag k by (1 - k/n). Throws core::InputError for fewer than 2 samples, a non-finite sample,
/// a non-positive rate, or constant data (no correlation to normalise).
Autocorrelation autocorrelation(std::span<const double> data, double sample_rate_hz,
                                std::size_t max_lag);

}  // namespace calstand::solver

#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "noise/allan.hpp"
#include "noise/wavelet_moments.hpp"

namespace calstand::solver {

/// The overlapping Allan, Hadamard and modified Allan variances of a rate record at octave
/// averaging factors m = 1, 2, 4, ..., computed while the record streams past in blocks of any
/// size, in memory that does not grow with the record (a day at 1 kHz, 86.4 million samples,
/// in about 15 MB). docs/noise-id.md, "Long records".
///
/// Up to m = exact_max_m (2^15 by default) every start sample is used, as allan() does: one
/// buffer of the last 3 exact_max_m phase points serves all those scales. Beyond it the same
/// estimator runs with start indices every D = m / exact_max_m samples, on the phase sampled
/// every D points (Allan, Hadamard) or averaged over blocks of D points (modified Allan, whose
/// phase averages over m are exact sums of those block means): every difference term is exact
/// and the expectation is unchanged; only the overlap between starts closer than D is dropped,
/// and D / m = 1 / exact_max_m is far below the correlation length m of the differences, so
/// the variance of the estimate grows by a negligible share (the tests measure it). The
/// reported `terms` count the differences summed; the EDF and intervals are those of the
/// full-overlap estimator.
///
/// Numerics: there is no pass for the mean, so the mean of the first 65,536 samples (or of all,
/// if fewer) is subtracted before the phase is summed (the second and third differences ignore
/// a constant rate exactly); the phase is summed in double from an origin (long double) moved
/// every 4096 samples, and each scale level stores it relative to an anchor (long double)
/// moved to its newest point at each buffer shift, so the sums and the stored values stay
/// bounded by the phase's excursion over 4096 samples or a buffer, whatever the bias and the
/// length. The results do not depend on how the record is split into blocks.
///
/// Noise types: the lag-1 identification allan() makes at each tau (identify_noise_lag1(): the
/// phase decimated by m, differenced up to 2 or 3 times) is accumulated for every octave m at
/// once from the full-rate phase, a Lag1Accumulator per m (count, sum, sum of squares, sum of
/// neighbour products, first and last value per difference order): O(log N) memory. The phase
/// here has the first block's mean rate removed, allan()'s the whole record's; the difference,
/// a linear ramp, is taken out of the sums at result() time, so the types, EDFs and intervals
/// are allan()'s (up to the rounding of one-pass sums, which moves a type only when its
/// autocorrelation sits on a rounding boundary).
class DeviationStream {
 public:
  /// Default exact range: every start sample up to m = 2^15 (32.8 s at 1 kHz).
  static constexpr std::size_t kExactMaxM = std::size_t{1} << 15U;

  /// Accumulates the variances of `kinds` (kAllan, kHadamard, kModified; kAllan also gives
  /// wavelet_moments()). exact_max_m: a power of two >= 4. Throws core::InputError naming the
  /// field for an empty or unsupported kind (the non-overlapping Hadamard) or a bad exact_max_m.
  explicit DeviationStream(std::vector<AllanKind> kinds, std::size_t exact_max_m = kExactMaxM);
  ~DeviationStream();
  DeviationStream(DeviationStream&&) noexcept;
  DeviationStream& operator=(DeviationStream&&) noexcept;

  /// Appends rate samples (any block size, including 0). Throws core::InputError naming the
  /// sample's index in the whole record when one is not finite; the stream is then unusable.
  void push(std::span<const double> rate);
  /// Rate samples pushed so far.
  std::size_t samples() const;

  /// The deviation curve of `options.kind` (one of the constructor's kinds) at octave averaging
  /// factors up to max_averaging_factor(), with the noise type, EDF and intervals chosen as
  /// allan() chooses them. Throws core::InputError as allan() does (too few samples, bad
  /// options, a non-positive rate), and for a tau set other than octave (field "taus": a
  /// streamed record has the octave factors only) or a kind not accumulated.
  AllanResult result(double sample_rate_hz, const AllanOptions& options);

  /// The Haar wavelet variances wavelet_moments() gives (needs kAllan). Throws
  /// core::InputError as wavelet_moments() does.
  WaveletMoments moments(double sample_rate_hz);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace calstand::solver

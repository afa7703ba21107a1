#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::solver {

/// Which two-sample-family variance to estimate (NIST SP 1065 section 5.2), computed from the
/// cumulative sum of the rate data. All but kHadamardNonOverlapping use every start sample
/// (stride one), the estimators to use; the non-overlapping Hadamard deviation is there because
/// SP 1065's test-set table quotes it as "HDEV".
enum class AllanKind {
  kAllan,     ///< overlapping Allan deviation (OADEV), second difference of the phase
  kModified,  ///< modified Allan deviation (MDEV): the second difference averaged over m
  kHadamard,  ///< overlapping Hadamard deviation (OHDEV), third difference; blind to rate ramp
  kHadamardNonOverlapping,  ///< Hadamard deviation with stride m (SP 1065's HDEV)
};
/// "adev", "mdev", "ohdev", "hdev" (the names of SP 1065 and Stable32: plain HDEV is the
/// non-overlapping one).
std::string_view to_string(AllanKind kind);
/// Inverse of to_string. Throws core::InputError naming the text when it is none of them.
AllanKind parse_allan_kind(std::string_view text);

/// How the averaging times are chosen. Every tau is a whole multiple m of the sample period.
enum class TauSpacing {
  kOctave,    ///< m = 1, 2, 4, 8, ...
  kDecade,    ///< m = 1, 10, 100, ...
  kDense,     ///< about ten per decade, log-spaced (m = round(10^(k/10)), duplicates dropped)
  kExplicit,  ///< the averaging times of TauSet::taus_s, rounded to whole samples
};

/// A set of averaging times.
struct TauSet {
  TauSpacing spacing = TauSpacing::kOctave;
  std::vector<double> taus_s;  ///< [s], only for kExplicit

  /// Parses "octave", "decade", "dense" or a comma-separated list of averaging times in seconds
  /// ("0.1,1,10"). Throws core::InputError naming the text for an empty list, an entry that is
  /// not a finite positive number, or anything else.
  static TauSet parse(std::string_view text);
};

/// Largest averaging factor the estimator `kind` can evaluate on `samples` rate samples (at
/// least one difference term): samples/2 for Allan, samples/3 for modified and Hadamard.
std::size_t max_averaging_factor(AllanKind kind, std::size_t samples);

/// The averaging factors m (sorted, unique) of `taus` for `samples` samples at sample_rate_hz,
/// up to max_averaging_factor(). Explicit averaging times are rounded to the nearest whole
/// sample. Throws core::InputError when an explicit tau is shorter than half a sample period or
/// longer than the data allow (the message gives the allowed range), or when no tau fits.
std::vector<std::size_t> averaging_factors(const TauSet& taus, std::size_t samples,
                                           double sample_rate_hz, AllanKind kind);

/// Options of allan(); defaults give the overlapping Allan deviation at octave taus with
/// 68.3 % (one-sigma) confidence intervals and the noise type estimated at each tau.
struct AllanOptions {
  AllanKind kind = AllanKind::kAllan;
  TauSet taus;
  /// Two-sided probability of the confidence interval, in (0, 1).
  double confidence = 0.683;
  /// Power-law noise exponent alpha of S_y(f) ~ f^alpha used for the degrees of freedom:
  /// 2 white PM (quantization), 1 flicker PM, 0 white FM (angle/velocity random walk), -1
  /// flicker FM (bias instability), -2 random-walk FM (rate random walk); Hadamard also -3, -4.
  /// None: identified at each tau by the lag-1 autocorrelation, as Stable32 does (see allan()).
  std::optional<int> alpha;
  /// Compute equivalent degrees of freedom and intervals (false: only the deviations; edf, lo
  /// and hi are then NaN).
  bool intervals = true;

  /// Throws core::InputError naming the field: confidence outside (0, 1), alpha outside the
  /// range the estimator converges for (see equivalent_dof()), or a bad explicit tau list.
  void validate() const;
};

/// One averaging time of a deviation curve.
struct AllanPoint {
  std::size_t m = 0;       ///< averaging factor (samples per average)
  double tau_s = 0.0;      ///< averaging time m / sample_rate [s]
  double deviation = 0.0;  ///< estimated deviation [unit of the data]
  std::size_t terms = 0;   ///< number of difference terms summed
  int alpha = 0;           ///< noise exponent used for the degrees of freedom
  double edf = 0.0;        ///< equivalent degrees of freedom of the variance estimate
  double lo = 0.0;         ///< lower end of the confidence interval [unit]
  double hi = 0.0;         ///< upper end of the confidence interval [unit]
};

/// A deviation curve and how it was made.
struct AllanResult {
  AllanKind kind = AllanKind::kAllan;
  double sample_rate_hz = 0.0;
  std::size_t samples = 0;
  double confidence = 0.0;
  std::vector<AllanPoint> points;  ///< by increasing tau
};

/// The deviation curve of rate (frequency-type) data `rate` sampled at sample_rate_hz: a gyro
/// rate in deg/s gives deviations in deg/s, an accelerometer in m/s^2 gives m/s^2.
///
/// The data's mean is removed first (no estimator here sees a constant) and the phase is its
/// cumulative sum, so each tau costs one pass over the data (the Allan taus share one blocked
/// pass). Confidence intervals come from equivalent_dof() and chi-square quantiles.
///
/// Without options.alpha the noise type at each tau is identified by the lag-1 autocorrelation
/// of the phase decimated by m (identify_noise_lag1(), Riley and Greenhall 2004; NIST SP 1065
/// 5.5.5), as Stable32 and the total deviations do: it depends on the record and the tau alone,
/// not on the other taus asked for. Beyond the last tau the method reaches (30 decimated points,
/// about N / 29), the type identified at the longest octave tau it reaches
/// (lag1_longest_octave_factor()) is carried, whatever the tau set, white FM if it named none
/// (Stable32 switches to the B1 ratio there; not implemented).
///
/// A phase-noise EDF (white or flicker PM), which grows with the sample count, is bounded by
/// the data length: by the white-FM EDF at that tau (about 3 N / (2 m), the most any frequency
/// noise gives) divided by the squared share of frequency noise in the variance (reasoning in
/// allan.cpp). Where the type was identified the share is read from the local slope of the
/// curve (fitted over the taus within a factor of 2), which leaves a pure phase-noise tau its
/// EDF and bounds one the method names phase noise while frequency noise holds a fair share;
/// where phase noise was carried the share is taken as 1 (white FM's EDF). Give alpha to
/// override (no bound is applied then).
///
/// Throws core::InputError for empty or too short data (fewer than 2 samples, 3 for the
/// others), a non-finite sample (its index is named), a non-positive or non-finite rate,
/// or invalid options. Thread safe (no shared state).
AllanResult allan(std::span<const double> rate, double sample_rate_hz,
                  const AllanOptions& options = {});

/// The deviation curve allan() gives once the variances are known: `var[k]` is the variance at
/// averaging factor ms[k] (increasing), summed over terms[k] difference terms, of a record of
/// `samples` rate samples. The EDF and intervals are chosen exactly as allan() chooses them
/// (options.taus is not used), from the noise types the caller identified as allan() does:
/// `identified[k]` the lag-1 type at ms[k] (nullopt where the method cannot tell), `carried`
/// the one at lag1_longest_octave_factor(samples). For an estimator that computes the variances
/// another way (solver::DeviationStream, a streamed record). Unless options.alpha is given or
/// options.intervals is false, `identified` must hold one entry per m (std::logic_error).
AllanResult allan_result_from_variances(std::span<const std::size_t> ms,
                                        std::span<const double> var,
                                        std::span<const std::size_t> terms, std::size_t samples,
                                        double sample_rate_hz, const AllanOptions& options,
                                        std::span<const std::optional<int>> identified,
                                        std::optional<int> carried);

/// The variance of `kind` at averaging factor m of the rate samples whose phase (cumulative sum
/// in sample units, phase[0] = 0, phase.size() = samples + 1) is given; the building block of
/// allan(), exposed for the benchmark and tests. `m` must be in [1, max_averaging_factor()].
double allan_variance_from_phase(std::span<const double> phase, std::size_t m, AllanKind kind);

/// Cumulative sum of `rate` minus its mean, with phase[0] = 0, in rate * samples (multiply by
/// the sample period for time units). Throws core::InputError for a non-finite sample.
std::vector<double> phase_from_rate(std::span<const double> rate);

}  // namespace calstand::solver

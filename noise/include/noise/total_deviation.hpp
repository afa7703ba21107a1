#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "noise/allan.hpp"

namespace calstand::solver {

/// The total and Theo family of deviations (NIST SP 1065, sections 5.2.11 to 5.2.15): the same
/// quantities as the Allan, modified Allan and Hadamard deviations, estimated with less
/// variance at the long taus of a record (where an IMU's bias instability and rate random walk
/// are read) by extending the data by reflection (the totals) or by a wider kernel (Theo1).
enum class TotalKind {
  kTotal,          ///< TOTDEV: Allan deviation of the phase extended by odd reflection
  kModifiedTotal,  ///< MTOTDEV: modified Allan deviation of 3m-point detrended, reflected runs
  kTimeTotal,      ///< TTOTDEV: tau / sqrt(3) MTOTDEV, in [unit * s]
  kHadamardTotal,  ///< HTOTDEV: Hadamard deviation of 3m-point detrended, reflected runs
  kTheo1,          ///< Theo1 at tau = 0.75 m tau0 (m even)
  kTheoBr,         ///< TheoBR: Theo1 with its bias removed by the record's own Allan variance
  kTheoH,          ///< TheoH: Allan deviation up to 10 % of the record, TheoBR beyond
};

/// "totdev", "mtotdev", "ttotdev", "htotdev", "theo1", "theobr", "theoh".
std::string_view to_string(TotalKind kind);
/// Inverse of to_string; nullopt when `text` names none of them (an Allan kind, say).
std::optional<TotalKind> parse_total_kind(std::string_view text);

/// Options of total_deviation(); the defaults are Stable32's: bias corrections where Stable32
/// applies them, 68.3 % intervals, the noise type identified at each tau by the lag-1
/// autocorrelation.
struct TotalOptions {
  TotalKind kind = TotalKind::kTotal;
  /// For the Theo kinds the averaging times are tau = 0.75 m tau0 with m even (explicit taus
  /// are rounded to the nearest such m; octave and decade give m = 2, 4, 8, ... and 10, 100,
  /// ...); for the others tau = m tau0 as for allan().
  TauSet taus;
  double confidence = 0.683;  ///< two-sided probability of the interval, in (0, 1)
  /// Power-law noise exponent (S_y ~ f^alpha) for the bias correction and the EDF, as
  /// Stable32's "alpha" field; none: identified at each tau (noise_identification.hpp).
  std::optional<int> alpha;
  /// Apply the bias corrections Stable32 applies: TOTVAR for flicker and random-walk FM,
  /// HTOTVAR for alpha 0 to -4 at m > 1, Theo1 per Howe and Tasset for the Theo1 kind. MTOTVAR
  /// and TTOTVAR are left raw, as Stable32 leaves them. TheoBR/TheoH remove Theo1's bias by
  /// their definition whatever this says.
  bool bias_correction = true;
  bool intervals = true;  ///< false: edf, lo and hi are NaN

  /// Throws core::InputError naming the field (confidence, alpha, taus).
  void validate() const;
};

/// A curve of a total or Theo deviation; points are as allan()'s (alpha is the noise type used
/// for the bias and the EDF, `terms` the number of squared differences summed).
struct TotalResult {
  TotalKind kind = TotalKind::kTotal;
  double sample_rate_hz = 0.0;
  std::size_t samples = 0;
  double confidence = 0.0;
  bool bias_corrected = false;
  std::vector<AllanPoint> points;  ///< by increasing tau
};

/// The total or Theo deviation of rate (frequency-type) data `rate` at sample_rate_hz, in the
/// rate's unit (TTOTDEV: unit * s). The phase is the cumulative sum of the mean-free rate, as
/// allan() uses; every estimator here cancels a constant rate. Memory O(N); time O(N) per tau
/// for TOTDEV, O(N m) for MTOTDEV, TTOTDEV, HTOTDEV and Theo1 (their definitions' cost: use
/// them on records of up to about 1e5 samples at long taus).
///
/// Throws core::InputError for too short data (fewer than 8 samples, 24 for TheoBR and
/// TheoH), a non-finite sample (its index named), a non-positive rate or invalid options.
/// Thread safe.
TotalResult total_deviation(std::span<const double> rate, double sample_rate_hz,
                            const TotalOptions& options = {});

/// The raw (uncorrected) variance of `kind` at averaging factor m of the phase `x` (in sample
/// units of the rate, N points), as SP 1065 defines it; the building block of
/// total_deviation(), exposed for the tests. For kTheo1 m must be even (tau = 0.75 m). Not for
/// kTheoBr and kTheoH (whole-record statistics). Throws core::InputError for an m out of range.
double total_variance_from_phase(std::span<const double> x, std::size_t m, TotalKind kind);

/// TheoBR's bias factor of a phase record of N points (SP 1065 eq. 32): the mean over i = 0 ..
/// floor(N / 6 - 3) of AVAR(m = 9 + 3 i) / Theo1(m = 12 + 4 i), the same tau in both. Throws
/// core::InputError for N < 24.
double theo_br_bias(std::span<const double> x);

/// The factor the raw variance of `kind` is multiplied by to remove its bias for noise exponent
/// alpha at averaging factor m of N phase points; 1 where there is none. TOTVAR: 1 / (1 - a m /
/// N); HTOTVAR: 1 / (1 + a) above m = 1; Theo1: Howe and Tasset's AVAR/Theo1 = a + b / (0.75
/// m)^c; MTOTVAR and TTOTVAR: 1 / (MTOT/MVAR ratio), which total_deviation() does not apply
/// (Stable32 does not) but SP 1065's test-set table does.
double total_bias_factor(TotalKind kind, int alpha, std::size_t m, std::size_t phase_points);

/// The noise exponent whose nominal AVAR/Theo1 ratio (2: 0.4, 1: 0.6, 0: 1.0, -1: 1.71, -2:
/// 2.24) is nearest, on a log scale, to a TheoBR bias factor: the noise type Stable32 prints
/// for a TheoBR run. total_deviation() does not use it for the EDF (see there).
int theo_br_noise_type(double bias);

/// Equivalent degrees of freedom of `kind` at averaging factor m of N phase points for noise
/// exponent alpha (SP 1065 section 5.3.3 and Table 7 to 9 forms; Greenhall and Riley's
/// algorithm for the Hadamard total at m < 16 and for noise types the tables do not cover).
/// Returns at least 1.
double total_equivalent_dof(TotalKind kind, int alpha, std::size_t m, std::size_t phase_points);

}  // namespace calstand::solver

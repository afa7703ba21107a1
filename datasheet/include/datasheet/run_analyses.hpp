#pragma once
// Which datasheet analyses of the seed's test catalogue a run supports, decided in one place
// from its recorded steps, and their results: for `calstand report`'s "Datasheet figures" and
// `calstand analyze all`.

#include <array>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "datasheet/bandwidth.hpp"
#include "datasheet/hysteresis.hpp"
#include "datasheet/repeatability.hpp"
#include "datasheet/stability.hpp"
#include "datasheet/warmup.hpp"
#include "noise/run_noise.hpp"
#include "store/database.hpp"
#include "store/records.hpp"

namespace calstand::analysis {

/// The datasheet analyses, in the order a report shows them.
enum class DatasheetKind { kRepeatability, kWarmup, kStability, kHysteresis, kBandwidth };
inline constexpr std::array<DatasheetKind, 5> kDatasheetKinds = {
    DatasheetKind::kRepeatability, DatasheetKind::kWarmup, DatasheetKind::kStability,
    DatasheetKind::kHysteresis, DatasheetKind::kBandwidth};

/// The KIND of `calstand analyze`: "repeatability", "warmup", "stability", "hysteresis",
/// "bandwidth".
std::string_view to_string(DatasheetKind kind);

/// What the test is called on a datasheet and a page: "bias repeatability", "warm-up", ...
std::string_view title(DatasheetKind kind);

/// A capture that starts within this of a power-up holds the power-on transient from its start
/// (the warm-up procedure records from its first sample) [s].
inline constexpr double kPowerOnCaptureMaxSettleS = 1.0;

/// What a run's recorded steps say about one analysis.
struct DatasheetApplicability {
  DatasheetKind kind = DatasheetKind::kRepeatability;
  /// The run holds what the analysis measures: power-ups each followed by captures
  /// (repeatability), a capture starting at a power-up (warm-up), a static capture of
  /// kMinNoiseRecordS or more that does not start at a power-up (stability), a temperature
  /// staircase with captures at a set point reached from below and from above (hysteresis), an
  /// oscillate step (bandwidth).
  bool applies = false;
  /// In words: what in the run makes it apply ("12 power-ups, each followed by a capture"), or
  /// what it lacks ("no oscillate step").
  std::string evidence;
  /// Warm-up and stability: the capture to analyse.
  std::optional<std::size_t> step;
};

/// One entry per kind (kDatasheetKinds order), from the run's steps as stored (completed steps
/// only count). Reads no samples.
std::vector<DatasheetApplicability> datasheet_applicability(
    const std::vector<store::StepRecord>& steps);

/// Settings of the analyses that take any.
struct DatasheetOptions {
  double warmup_band_deg_per_h = 1.0;  ///< a gyro bias this close to its settled value is settled
  double warmup_band_ug = 50.0;        ///< ... an accelerometer bias
  /// The noise analysis of the stability capture when the caller has made it already, at the
  /// default (octave) averaging times (stability_of()): the report reads a long capture once
  /// for its Allan plot and the stability figures. Used when it is of the capture the
  /// applicability names, else the analysis reads the capture. Not owned; must outlive the call.
  const solver::RunNoise* stability_noise = nullptr;
};

/// The analyses that apply to a run and what each gave.
struct DatasheetAnalyses {
  std::int64_t run = 0;
  std::string device;
  std::vector<DatasheetApplicability> applicability;  ///< every kind, kDatasheetKinds order
  std::optional<RepeatabilityAnalysis> repeatability;
  std::optional<WarmupAnalysis> warmup;
  std::optional<StabilityAnalysis> stability;
  std::optional<HysteresisAnalysis> hysteresis;
  std::optional<BandwidthAnalysis> bandwidth;
  /// Per kind (kDatasheetKinds order): why an analysis that applies has no result (the
  /// analysis refused the run's data: its core::InputError's message), or "".
  std::array<std::string, 5> failure;

  bool has_result(DatasheetKind kind) const;
  const DatasheetApplicability& applicability_of(DatasheetKind kind) const;
  const std::string& failure_of(DatasheetKind kind) const;
};

/// Decides which analyses apply to `run` for `device` ("" = the run's only IMU) and makes
/// those. An analysis that applies but refuses the data with core::InputError (its own checks:
/// too short a capture, cycles of different lengths, a staircase without leg loop values) has
/// its message in `failure`; any other error propagates, as does an unknown run (RunNotFound),
/// a run without samples (NothingToFit) or an unknown device (core::InputError).
DatasheetAnalyses run_datasheet_analyses(store::Database& db, std::int64_t run,
                                         const std::string& device,
                                         const DatasheetOptions& options = {});

/// `{"run", "device", "analyses": {KIND: the analysis's to_json(), ...},
///   "missing": {KIND: why, ...}, "not_applicable": {KIND: why, ...},
///   "evidence": {KIND: what made it apply, ...}}`
nlohmann::json to_json(const DatasheetAnalyses& a);

}  // namespace calstand::analysis

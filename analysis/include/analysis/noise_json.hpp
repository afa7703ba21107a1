#pragma once
// Noise analysis results as JSON (calstand allan|noise --json, the calibration record's noise
// figures) and when a run's static record is long enough to be worth analysing.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "noise/allan.hpp"
#include "noise/model_figures.hpp"
#include "noise/noise_fit.hpp"
#include "noise/record_length.hpp"
#include "noise/run_noise.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// A static record this long or longer is worth its noise analysis: the report shows its Allan
/// deviation and a calibration record carries its noise figures [s]. The bias instability sits
/// at the flat bottom of the Allan curve, typically at averaging times of tens to hundreds of
/// seconds, and the curve's confidence there needs the record to be several times longer; a
/// shorter record resolves only the white noise. (The report and the calibration used to
/// disagree: 600 s and 100 s.)
inline constexpr double kMinNoiseRecordS = 600.0;

/// True when a static record spanning `duration_s` from its first to its last sample is long
/// enough: at least kMinNoiseRecordS less 1 %, because a capture commanded as 600 s spans a
/// sample period less than that (and a device clock may run slightly slow).
bool long_enough_for_noise(double duration_s);

/// The fitted IEEE 952 terms in the data's unit `unit` (what the fit works in): quantization,
/// random_walk, bias_instability, rate_random_walk, rate_ramp (each value, sigma, resolved,
/// unit), min_deviation, min_tau_s, bias_instability_from_min, chi2_dof, unit.
nlohmann::ordered_json noise_terms_json(const solver::NoiseTerms& terms, const std::string& unit);

/// Datasheet figures (name, label, value, sigma or null, unit, resolved), in order.
nlohmann::ordered_json datasheet_figures_json(const std::vector<solver::DatasheetFigure>& figures);

/// `calstand noise --json` without the Kalibr file: run, device, step, step_label, samples,
/// sample_rate_hz, duration_s, gaps and per channel its figures and terms.
nlohmann::ordered_json run_noise_json(const solver::RunNoise& noise);

/// What the record gives against what each noise figure needs (solver::record_length_needs()):
/// {"record_length_s", "rule": {"confidence", "half_width", "required_edf", "text"},
///  "gyro": {"random_walk": {"tau_s", "alpha", "channel", "needed_s", "enough", "located"},
///           "bias_instability": {...}, "rate_random_walk": {...}}, "accel": {...}}.
nlohmann::ordered_json record_length_json(const solver::RunNoise& noise,
                                          const solver::RecordLengthRule& rule = {});

/// How the noise terms of data in `unit` become datasheet figures (solver::datasheet_figures
/// works in deg/s and m/s^2): a gyro unit (deg/s, rad/s) or an accelerometer unit (m/s^2, g =
/// g0 = 9.80665 m/s^2), and the factor from `unit` to deg/s or m/s^2.
struct DatasheetUnit {
  bool gyro = true;
  double to_base = 1.0;
};
/// The datasheet unit of `unit`; none for any other unit (the data are then only labelled).
std::optional<DatasheetUnit> datasheet_unit(const std::string& unit);

/// `terms` of data multiplied by `k` (a change of unit): every coefficient, sigma and the
/// Allan minimum scale with the data; tau, chi2/dof and the point count do not.
solver::NoiseTerms scale_noise_terms(const solver::NoiseTerms& terms, double k);

/// `calstand allan --json`: the curve of `source` (kind, unit, rate, samples, confidence, tau,
/// deviation with its interval, edf, alpha) and the fitted terms (null when there are none);
/// `datasheet` adds the datasheet figures of a gyro or accelerometer channel whose data are in
/// `unit` (terms scaled by its to_base first).
nlohmann::ordered_json allan_json(const solver::AllanResult& result, const std::string& source,
                                  const std::string& kind, const std::string& unit,
                                  double sample_rate_hz,
                                  const std::optional<solver::NoiseTerms>& terms,
                                  std::optional<DatasheetUnit> datasheet);

/// The run's noise figures in datasheet units from its longest static capture, for a
/// calibration record: {"step", "duration_s", "sample_rate_hz", "channels": {"gx": [figures...],
/// ...}, "model_figures": {"gx": [...], ...}}, or null when the run has no static capture at
/// least kMinNoiseRecordS long. "channels" holds the Allan-line figures (what factory acceptance
/// reads); "model_figures" each channel's figures from its identified composite model where the
/// record supports it, else the Allan line's, each naming its estimator
/// (solver::channel_noise_models(), channel_model_figures_json()'s "model_figures").
nlohmann::json calibration_noise_figures(store::Database& db, std::int64_t run,
                                         const std::string& device);

/// A calibration record's "noise" (calibration_noise_figures()) read back into noise terms, for
/// the exports that need them in the data's unit (solver::kalibr_from_run_noise): per channel
/// gx..az the random walk N and rate random walk K converted from their datasheet figures
/// (angle/velocity random walk, rate/acceleration random walk) with their "resolved" flags;
/// sample_rate_hz, 0 for a record written before it was stored. None when `noise` is null or
/// absent. Throws core::InputError naming the channel and figure when one is missing or its unit
/// does not convert.
std::optional<solver::RunNoise> calibration_noise_terms(const nlohmann::json& noise);

/// A calibration record's "noise.model_figures" read back per channel gx..az (figures only, no
/// model), the white density and random walk converted to the data's unit (deg/s/sqrt(Hz),
/// deg/s/sqrt(s); m/s^2 likewise) for solver::kalibr_from_noise_models(). None when `noise` is
/// null or has no "model_figures" (records written before they were kept). Throws
/// core::InputError naming the channel and figure when one is malformed or its unit does not
/// convert.
std::optional<std::vector<solver::ChannelModelFigures>> calibration_noise_models(
    const nlohmann::json& noise);

}  // namespace calstand::analysis

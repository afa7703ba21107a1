#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/imu_sample.hpp"
#include "noise/allan.hpp"
#include "noise/noise_fit.hpp"
#include "noise/wavelet_moments.hpp"
#include "store/database.hpp"

namespace calstand::solver {

/// The six output channels of an IMU sample: gyro x y z [deg/s], accelerometer x y z [m/s^2].
enum class ImuChannel { kGx, kGy, kGz, kAx, kAy, kAz };
inline constexpr ImuChannel kAllChannels[] = {ImuChannel::kGx, ImuChannel::kGy, ImuChannel::kGz,
                                              ImuChannel::kAx, ImuChannel::kAy, ImuChannel::kAz};
std::string_view to_string(ImuChannel channel);  ///< "gx" ... "az"
/// Inverse of to_string. Throws core::InputError listing the channels for anything else.
ImuChannel parse_channel(std::string_view text);
bool is_gyro(ImuChannel channel);
std::string_view channel_unit(ImuChannel channel);  ///< "deg/s" or "m/s^2"

/// One channel of `samples`, in its unit (channel_unit()).
std::vector<double> channel_series(std::span<const core::ImuSample> samples, ImuChannel channel);

/// The sample rate [Hz] of `samples` from their device clock: (n - 1) over the time spanned.
/// Throws core::InputError for fewer than 2 samples or a clock that does not advance.
double sample_rate_of(std::span<const core::ImuSample> samples);

/// A noise figure in the unit datasheets quote it in.
struct DatasheetFigure {
  std::string name;   ///< e.g. "angle_random_walk"
  std::string label;  ///< e.g. "angle random walk N"
  double value = 0.0;
  double sigma = 0.0;    ///< one sigma, same unit; NaN for figures read off the curve
  std::string unit;      ///< e.g. "deg/sqrt(h)", "ug"
  bool resolved = true;  ///< false: the fit found no evidence of the term (value 0)
};

/// The noise terms of a gyro (data in deg/s) or accelerometer (m/s^2) channel in datasheet
/// units. Gyro: angle random walk [deg/sqrt(h)], bias instability as the Allan minimum and as
/// minimum / 0.664 and as fitted [deg/h], rate random walk [deg/h/sqrt(h)], rate ramp
/// [deg/h/h], angle quantization [arcsec]. Accelerometer: velocity random walk [m/s/sqrt(h)],
/// bias instability (the same three) [ug], acceleration random walk [m/s/h/sqrt(h)],
/// acceleration ramp [m/s/h/h], velocity quantization [m/s].
std::vector<DatasheetFigure> datasheet_figures(const NoiseTerms& terms, bool gyro);

/// The Allan curve, fitted noise terms and datasheet figures of one channel.
struct ChannelNoise {
  ImuChannel channel = ImuChannel::kGx;
  AllanResult allan;
  NoiseTerms terms;  ///< in the channel's unit (deg/s or m/s^2 based, see NoiseTerms)
  std::vector<DatasheetFigure> figures;
  /// The record's Haar wavelet variances, set by analyse_run_noise() (none from
  /// analyse_noise_samples(), or for fewer than 32 samples): channel_noise_models(db, ...)
  /// identifies the model from them instead of reading the step a second time.
  std::optional<WaveletMoments> moments;
};

/// Options of analyse_run_noise().
struct RunNoiseOptions {
  std::string device;               ///< IMU name; empty: the first with samples (sorted)
  std::optional<std::size_t> step;  ///< step index; none: see choose_noise_step()
  AllanOptions allan;               ///< must be kAllan (the noise model is the Allan variance's)
  NoiseFitOptions fit;              ///< its min_tau_s is raised to min_tau_samples periods
  /// The fit leaves out averaging times shorter than this many sample periods, where the
  /// IMU's anti-aliasing filter lowers the curve (a simulated LN200 at 400 Hz with a 100 Hz
  /// bandwidth reads 7 % under its white-noise line at 4 samples, 3 % at 10, 1 % at 20).
  double min_tau_samples = 20.0;
};

/// The noise analysis of one step of a run for one IMU.
struct RunNoise {
  std::int64_t run = 0;
  std::string device;
  std::size_t step = 0;
  std::string step_label;
  std::size_t samples = 0;
  double sample_rate_hz = 0.0;
  double duration_s = 0.0;
  /// Intervals of the device clock longer than 1.5 sample periods: lost samples, which the
  /// Allan variance (it assumes an unbroken series) does not see; shown so they are not missed.
  std::size_t gaps = 0;
  std::vector<ChannelNoise> channels;  ///< gx gy gz ax ay az
};

/// The step a noise analysis of `run` uses: `step` when given, else the completed capture step
/// (the table at rest) with the longest duration on the station clock. Throws core::InputError
/// when the run or step does not exist, or the run has no completed capture step.
std::size_t choose_noise_step(store::Database& db, std::int64_t run,
                              std::optional<std::size_t> step);

/// True when every completed step of `run` with samples lies at rest by the rule
/// choose_noise_step() applies to a step recorded without a table (its gyros scatter by at most
/// 1 deg/s): a static recording, such as an imported bag at rest. Reads the step means only, no
/// sample. False for a run without completed steps with samples.
bool run_is_at_rest(store::Database& db, std::int64_t run);

/// The IMU whose samples a noise analysis of `run` reads: `device` when given, else the first
/// with samples (sorted). Throws core::InputError when the run holds no samples.
std::string noise_device(store::Database& db, std::int64_t run, const std::string& device);

/// The noise analysis of `samples` (one record at rest of one IMU, in time order) as
/// analyse_run_noise() makes it of a step, for a caller that holds the samples already (the
/// report reads a run once); run, device, step and step_label are the caller's to set. Throws
/// core::InputError for fewer than 2 samples, a device clock that does not advance, too few
/// samples for a curve, or invalid options.
RunNoise analyse_noise_samples(std::span<const core::ImuSample> samples,
                               const RunNoiseOptions& options = {});

/// Reads the samples of the chosen step (the store's data attempt) and computes, per channel,
/// the Allan deviation curve with its intervals and the fitted noise terms. With octave taus
/// (the default) the step streams chunk by chunk, decoded once, through one DeviationStream
/// per channel in memory that does not grow with the step (a day at 1 kHz fits); the result
/// equals analyse_noise_samples() on the same samples to rounding up to 2^17 samples and
/// within about 1e-6 beyond (docs/noise-id.md, "Long records"), and each channel keeps its
/// wavelet moments. Other tau sets read the whole step into memory (once: the moments are
/// kept as well). Throws
/// core::InputError when the run, step or device does not exist, the step holds no samples of
/// the device, too few for a curve, or the options are invalid; store::StoreError on a
/// database failure.
RunNoise analyse_run_noise(store::Database& db, std::int64_t run,
                           const RunNoiseOptions& options = {});

}  // namespace calstand::solver

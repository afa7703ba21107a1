// Noise analysis of a recorded run: the static step's samples, per channel Allan curve and
// noise terms, and the datasheet units.
#include "noise/run_noise.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "noise/deviation_stream.hpp"
#include "store/records.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"
#include "store/step_data.hpp"

namespace calstand::solver {
namespace {

constexpr double kSecondsPerHour = 3600.0;
constexpr double kSqrtSecondsPerHour = 60.0;  // 1/sqrt(s) = 60/sqrt(h)
constexpr double kMicroG = 9.80665e-6;        // [m/s^2]

DatasheetFigure figure(std::string name, std::string label, const NoiseTerm& t, double scale,
                       std::string unit) {
  return {std::move(name), std::move(label), t.value * scale,
          t.sigma * scale, std::move(unit),  t.resolved};
}

DatasheetFigure read_off(std::string name, std::string label, double value, std::string unit) {
  return {std::move(name), std::move(label),
          value,           std::numeric_limits<double>::quiet_NaN(),
          std::move(unit), true};
}

}  // namespace

std::string_view to_string(ImuChannel channel) {
  switch (channel) {
    case ImuChannel::kGx:
      return "gx";
    case ImuChannel::kGy:
      return "gy";
    case ImuChannel::kGz:
      return "gz";
    case ImuChannel::kAx:
      return "ax";
    case ImuChannel::kAy:
      return "ay";
    case ImuChannel::kAz:
      return "az";
  }
  return "?";
}

ImuChannel parse_channel(std::string_view text) {
  for (const ImuChannel c : kAllChannels) {
    if (text == to_string(c)) return c;
  }
  throw core::InputError("channel", fmt::format("'{}' is not one of gx, gy, gz, ax, ay, az", text));
}

bool is_gyro(ImuChannel channel) {
  return channel == ImuChannel::kGx || channel == ImuChannel::kGy || channel == ImuChannel::kGz;
}

std::string_view channel_unit(ImuChannel channel) { return is_gyro(channel) ? "deg/s" : "m/s^2"; }

std::vector<double> channel_series(std::span<const core::ImuSample> samples, ImuChannel channel) {
  const auto axis = static_cast<Eigen::Index>(static_cast<int>(channel) % 3);
  std::vector<double> out;
  out.reserve(samples.size());
  for (const core::ImuSample& s : samples) {
    out.push_back(is_gyro(channel) ? s.gyro_dps(axis) : s.accel_mps2(axis));
  }
  return out;
}

double sample_rate_of(std::span<const core::ImuSample> samples) {
  if (samples.size() < 2) {
    throw core::InputError("samples",
                           fmt::format("{} samples; a sample rate needs 2", samples.size()));
  }
  const double span = samples.back().device_time_s - samples.front().device_time_s;
  if (!(span > 0.0) || !std::isfinite(span)) {
    throw core::InputError("samples", "the device clock does not advance over the samples");
  }
  return static_cast<double>(samples.size() - 1) / span;
}

std::vector<DatasheetFigure> datasheet_figures(const NoiseTerms& t, bool gyro) {
  std::vector<DatasheetFigure> f;
  const double floor_factor = flicker_floor_factor();
  if (gyro) {
    // deg/s based: N [deg/sqrt(s)], B [deg/s], K [deg/s/sqrt(s)], R [deg/s^2], Q [deg].
    f.push_back(figure("angle_random_walk", "angle random walk N", t.random_walk,
                       kSqrtSecondsPerHour, "deg/sqrt(h)"));
    f.push_back(read_off("bias_instability_min", "bias instability, Allan minimum",
                         t.min_deviation * kSecondsPerHour, "deg/h"));
    f.push_back(read_off("bias_instability_min_coefficient",
                         fmt::format("bias instability B = minimum / {:.3f}", floor_factor),
                         t.bias_instability_from_min * kSecondsPerHour, "deg/h"));
    f.push_back(figure("bias_instability_fit", "bias instability B, fitted", t.bias_instability,
                       kSecondsPerHour, "deg/h"));
    f.push_back(figure("rate_random_walk", "rate random walk K", t.rate_random_walk,
                       kSecondsPerHour * kSqrtSecondsPerHour, "deg/h/sqrt(h)"));
    f.push_back(figure("rate_ramp", "rate ramp R", t.rate_ramp, kSecondsPerHour * kSecondsPerHour,
                       "deg/h/h"));
    f.push_back(figure("angle_quantization", "angle quantization Q", t.quantization,
                       kSecondsPerHour, "arcsec"));
  } else {
    // m/s^2 based: N [m/s/sqrt(s)], B [m/s^2], K [m/s^2/sqrt(s)], R [m/s^3], Q [m/s].
    f.push_back(figure("velocity_random_walk", "velocity random walk N", t.random_walk,
                       kSqrtSecondsPerHour, "m/s/sqrt(h)"));
    f.push_back(read_off("bias_instability_min", "bias instability, Allan minimum",
                         t.min_deviation / kMicroG, "ug"));
    f.push_back(read_off("bias_instability_min_coefficient",
                         fmt::format("bias instability B = minimum / {:.3f}", floor_factor),
                         t.bias_instability_from_min / kMicroG, "ug"));
    f.push_back(figure("bias_instability_fit", "bias instability B, fitted", t.bias_instability,
                       1.0 / kMicroG, "ug"));
    f.push_back(figure("acceleration_random_walk", "acceleration random walk K", t.rate_random_walk,
                       kSecondsPerHour * kSqrtSecondsPerHour, "m/s/h/sqrt(h)"));
    f.push_back(figure("acceleration_ramp", "acceleration ramp R", t.rate_ramp,
                       kSecondsPerHour * kSecondsPerHour, "m/s/h/h"));
    f.push_back(
        figure("velocity_quantization", "velocity quantization Q", t.quantization, 1.0, "m/s"));
  }
  return f;
}

namespace {
// Gyro scatter [deg/s, 1 sigma of one sample] above which a step recorded without a table is
// not static: the white noise of any IMU calstand serves stays well below it at its output rate
// (a consumer MEMS of 0.01 deg/s/sqrt(Hz) at 1 kHz: 0.3 deg/s), while a unit turned by hand
// scatters by tens of deg/s.
constexpr double kMaxStaticGyroScatterDps = 1.0;
}  // namespace

bool run_is_at_rest(store::Database& db, std::int64_t run) {
  const std::vector<store::StepMean> means = store::read_step_means(db, run);
  return !means.empty() && std::all_of(means.begin(), means.end(), [](const store::StepMean& m) {
    return m.gyro_std_dps.maxCoeff() <= kMaxStaticGyroScatterDps;
  });
}

std::size_t choose_noise_step(store::Database& db, std::int64_t run,
                              std::optional<std::size_t> step) {
  store::RunStore runs(db);
  const std::vector<store::StepRecord> steps = runs.load_steps(run);  // throws for a bad run
  if (step) {
    if (*step >= steps.size()) {
      throw core::InputError("step", fmt::format("run {} has steps 0..{}, not {}", run,
                                                 steps.size() == 0 ? 0 : steps.size() - 1, *step));
    }
    return *step;
  }
  // A step recorded without a table (an import without `table`) may be a hand-turned session:
  // it counts as static only when its gyros scatter like a unit at rest.
  std::vector<std::size_t> moving;
  for (const store::StepMean& m : store::read_step_means(db, run)) {
    if (m.gyro_std_dps.maxCoeff() > kMaxStaticGyroScatterDps) moving.push_back(m.step_index);
  }
  std::optional<std::size_t> best;
  double best_s = -1.0;
  std::size_t skipped_moving = 0;
  for (const store::StepRecord& s : steps) {
    // A capture step records with the table at rest; rate steps turn it.
    if (s.kind != "capture" || s.status != store::StepStatus::kCompleted) continue;
    if (!store::orientation_known(s) &&
        std::find(moving.begin(), moving.end(), s.index) != moving.end()) {
      ++skipped_moving;
      continue;
    }
    const double length = s.started_clock_s && s.ended_clock_s
                              ? *s.ended_clock_s - *s.started_clock_s
                              : s.commanded.value("duration_s", 0.0);
    if (length > best_s) {
      best_s = length;
      best = s.index;
    }
  }
  if (!best) {
    throw core::InputError(
        "run", fmt::format("run {} has no completed static capture step{}; give the step to "
                           "analyse",
                           run,
                           skipped_moving > 0
                               ? fmt::format(" ({} recorded without a table turn: their gyros "
                                             "scatter by more than {:g} deg/s)",
                                             skipped_moving, kMaxStaticGyroScatterDps)
                               : std::string()));
  }
  return *best;
}

RunNoise analyse_noise_samples(std::span<const core::ImuSample> samples,
                               const RunNoiseOptions& options) {
  if (options.allan.kind != AllanKind::kAllan) {
    throw core::InputError("kind", "the noise terms are fitted to the Allan deviation (adev)");
  }
  options.allan.validate();
  options.fit.validate();
  RunNoise out;
  out.samples = samples.size();
  out.sample_rate_hz = sample_rate_of(samples);
  out.duration_s = samples.back().device_time_s - samples.front().device_time_s;
  const double period = 1.0 / out.sample_rate_hz;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    if (samples[i].device_time_s - samples[i - 1].device_time_s > 1.5 * period) ++out.gaps;
  }
  NoiseFitOptions fit = options.fit;
  fit.min_tau_s = std::max(fit.min_tau_s, options.min_tau_samples / out.sample_rate_hz);
  for (const ImuChannel c : kAllChannels) {
    ChannelNoise ch;
    ch.channel = c;
    ch.allan = allan(channel_series(samples, c), out.sample_rate_hz, options.allan);
    ch.terms = fit_noise_terms(ch.allan, fit);
    ch.figures = datasheet_figures(ch.terms, is_gyro(c));
    out.channels.push_back(std::move(ch));
  }
  return out;
}

std::string noise_device(store::Database& db, std::int64_t run, const std::string& device) {
  if (!device.empty()) return device;
  const std::vector<std::string> devices = store::sample_devices(db, run);
  if (devices.empty()) {
    throw core::InputError("run", fmt::format("run {} holds no IMU samples", run));
  }
  return devices.front();
}

namespace {

/// Intervals of the device clock longer than this many sample periods count as gaps (as
/// analyse_noise_samples() counts them).
constexpr double kGapPeriods = 1.5;
/// While streaming, the rate (hence the gap threshold) is not known until the last sample: the
/// intervals longer than this many periods of the first chunk are kept as candidates (a lost
/// sample doubles one), and counted against the final threshold at the end.
constexpr double kCandidatePeriods = 1.25;
/// More candidates than this (a clock that is not regular) are not kept; the gaps are then
/// counted in a second pass over the step once its rate is known.
constexpr std::size_t kMaxGapCandidates = std::size_t{1} << 20U;

/// One pass over a stored step: the six channels fed to their streams, the clock's span and
/// the intervals that may be gaps.
struct StreamedStep {
  std::vector<DeviationStream> streams;  // gx gy gz ax ay az
  std::size_t samples = 0;
  double first_s = 0.0;
  double last_s = 0.0;
  double candidate_threshold_s = 0.0;  // 0: not yet known (every interval is kept)
  std::vector<double> candidates;      // intervals longer than candidate_threshold_s [s]
  bool candidates_complete = true;     // false: too many; count the gaps in a second pass
};

void stream_step(store::Database& db, std::int64_t run, std::size_t step, const std::string& device,
                 StreamedStep& st) {
  for (std::size_t i = 0; i < std::size(kAllChannels); ++i) {
    st.streams.emplace_back(std::vector<AllanKind>{AllanKind::kAllan});
  }
  std::vector<double> values;
  store::for_each_chunk(
      db, run, step, device, [&](const store::ChunkInfo&, std::span<const core::ImuSample> chunk) {
        if (chunk.empty()) return;
        double previous_s = st.samples == 0 ? chunk.front().device_time_s : st.last_s;
        if (st.samples == 0) st.first_s = previous_s;
        const std::size_t first = st.samples == 0 ? 1 : 0;
        for (std::size_t i = first; i < chunk.size(); ++i) {
          const double dt = chunk[i].device_time_s - previous_s;
          previous_s = chunk[i].device_time_s;
          if (st.candidates_complete && dt > st.candidate_threshold_s) {
            st.candidates.push_back(dt);
            if (st.candidates.size() > kMaxGapCandidates) {
              st.candidates_complete = false;
              st.candidates = {};
            }
          }
        }
        st.samples += chunk.size();
        st.last_s = chunk.back().device_time_s;
        if (st.candidate_threshold_s == 0.0 && st.samples >= 2 && st.last_s > st.first_s) {
          // The first chunks' period: intervals kept so far below the threshold are dropped.
          st.candidate_threshold_s =
              kCandidatePeriods * (st.last_s - st.first_s) / static_cast<double>(st.samples - 1);
          std::erase_if(st.candidates, [&](double dt) { return !(dt > st.candidate_threshold_s); });
        }
        for (std::size_t c = 0; c < st.streams.size(); ++c) {
          const auto axis = static_cast<Eigen::Index>(c % 3);
          const bool gyro = c < 3;
          values.clear();
          for (const core::ImuSample& s : chunk) {
            values.push_back(gyro ? s.gyro_dps(axis) : s.accel_mps2(axis));
          }
          st.streams[c].push(values);
        }
      });
}

/// The gaps of a step whose rate is known, counted in a pass of their own (the fallback for an
/// irregular clock).
std::size_t count_gaps(store::Database& db, std::int64_t run, std::size_t step,
                       const std::string& device, double period_s) {
  std::size_t gaps = 0;
  bool started = false;
  double previous_s = 0.0;
  store::for_each_chunk(db, run, step, device,
                        [&](const store::ChunkInfo&, std::span<const core::ImuSample> chunk) {
                          for (const core::ImuSample& s : chunk) {
                            if (started && s.device_time_s - previous_s > kGapPeriods * period_s) {
                              ++gaps;
                            }
                            previous_s = s.device_time_s;
                            started = true;
                          }
                        });
  return gaps;
}

/// analyse_run_noise() for octave taus: one pass over the stored chunks.
RunNoise stream_run_noise(store::Database& db, std::int64_t run, std::size_t step,
                          const std::string& device, const RunNoiseOptions& options) {
  StreamedStep st;
  stream_step(db, run, step, device, st);
  if (st.samples == 0) {
    throw core::InputError(
        "device", fmt::format("step {} of run {} holds no samples of '{}'", step, run, device));
  }
  // As sample_rate_of(): (n - 1) over the time the device clock spans.
  if (st.samples < 2) {
    throw core::InputError("samples", fmt::format("{} samples; a sample rate needs 2", st.samples));
  }
  const double span = st.last_s - st.first_s;
  if (!(span > 0.0) || !std::isfinite(span)) {
    throw core::InputError("samples", "the device clock does not advance over the samples");
  }
  RunNoise out;
  out.samples = st.samples;
  out.sample_rate_hz = static_cast<double>(st.samples - 1) / span;
  out.duration_s = span;
  const double period = 1.0 / out.sample_rate_hz;
  const double gap_threshold_s = kGapPeriods * period;
  if (st.candidates_complete && gap_threshold_s >= st.candidate_threshold_s) {
    out.gaps =
        static_cast<std::size_t>(std::count_if(st.candidates.begin(), st.candidates.end(),
                                               [&](double dt) { return dt > gap_threshold_s; }));
  } else {
    out.gaps = count_gaps(db, run, step, device, period);
  }
  NoiseFitOptions fit = options.fit;
  fit.min_tau_s = std::max(fit.min_tau_s, options.min_tau_samples / out.sample_rate_hz);
  for (std::size_t i = 0; i < st.streams.size(); ++i) {
    ChannelNoise ch;
    ch.channel = kAllChannels[i];
    ch.allan = st.streams[i].result(out.sample_rate_hz, options.allan);
    ch.terms = fit_noise_terms(ch.allan, fit);
    ch.figures = datasheet_figures(ch.terms, is_gyro(ch.channel));
    if (st.samples >= 32) ch.moments = st.streams[i].moments(out.sample_rate_hz);
    out.channels.push_back(std::move(ch));
  }
  return out;
}

}  // namespace

RunNoise analyse_run_noise(store::Database& db, std::int64_t run, const RunNoiseOptions& options) {
  if (options.allan.kind != AllanKind::kAllan) {
    throw core::InputError("kind", "the noise terms are fitted to the Allan deviation (adev)");
  }
  options.allan.validate();
  options.fit.validate();
  const std::size_t step = choose_noise_step(db, run, options.step);
  const std::string device = noise_device(db, run, options.device);
  RunNoise out;
  if (options.allan.taus.spacing == TauSpacing::kOctave) {
    out = stream_run_noise(db, run, step, device, options);
  } else {
    const std::vector<core::ImuSample> samples = store::read_samples(db, run, step, device);
    if (samples.empty()) {
      throw core::InputError(
          "device", fmt::format("step {} of run {} holds no samples of '{}'", step, run, device));
    }
    out = analyse_noise_samples(samples, options);
    // The moments too, so that channel_noise_models(db, ...) need not read the step again.
    if (samples.size() >= 32) {
      for (ChannelNoise& c : out.channels) {
        c.moments = wavelet_moments(channel_series(samples, c.channel), out.sample_rate_hz);
      }
    }
  }
  out.run = run;
  out.step = step;
  out.device = device;
  store::RunStore runs(db);
  for (const store::StepRecord& s : runs.load_steps(run)) {
    if (s.index == out.step) out.step_label = s.label;
  }
  return out;
}

}  // namespace calstand::solver

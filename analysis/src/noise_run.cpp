#include "analysis/noise_run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "core/error.hpp"
#include "noise/run_noise.hpp"
#include "solver/octave_allan.hpp"
#include "solver/run_setup.hpp"
#include "store/run_store.hpp"

namespace calstand::analysis {
namespace {

// A flicker band reaches this many run spans, as the wander kernels' does: beyond the run, a
// slower component is a constant the bias absorbs.
constexpr double kFlickerBandSpans = 10.0;

}  // namespace

FlickerBand flicker_band_of(const solver::RunData& run) {
  std::vector<double> intervals;
  double first = 0.0, last = 0.0;
  bool any = false;
  for (const store::StepData& step : run.steps) {
    const auto& s = step.samples;
    if (s.empty()) continue;
    first = any ? std::min(first, s.front().receive_time_s) : s.front().receive_time_s;
    last = any ? std::max(last, s.back().receive_time_s) : s.back().receive_time_s;
    any = true;
    if (s.size() > 1) {
      intervals.push_back((s.back().receive_time_s - s.front().receive_time_s) /
                          static_cast<double>(s.size() - 1));
    }
  }
  if (intervals.empty()) {
    throw core::InputError("run", "no step has two samples: there is no time scale to weigh it at");
  }
  std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
  const double interval = intervals[intervals.size() / 2];
  FlickerBand band;
  band.tau_min_s = solver::kWhiteFitShortestBlockSamples * interval;
  band.tau_max_s = kFlickerBandSpans * std::max(last - first, band.tau_min_s);
  return band;
}

solver::KnownWander wander_from_models(std::span<const solver::ChannelModelFigures> channels,
                                       const FlickerBand& band, const std::string& source) {
  if (channels.size() != static_cast<std::size_t>(solver::kChannels)) {
    throw core::InputError(
        source, fmt::format("{} channels where gx gy gz ax ay az are needed", channels.size()));
  }
  solver::KnownWander out;
  out.source = source;
  for (std::size_t c = 0; c < channels.size(); ++c) {
    const solver::ChannelModelFigures& ch = channels[c];
    if (!ch.model) {
      throw core::InputError(source, fmt::format("channel {} has no noise model ({})",
                                                 solver::to_string(ch.channel), ch.note));
    }
    std::vector<solver::WanderModel> parts;
    for (const solver::NoiseModelTerm& t : ch.model->terms) {
      solver::WanderModel w;
      switch (t.kind) {
        case solver::NoiseKind::kGaussMarkov:
          w.kind = solver::WanderKind::kGaussMarkov;
          w.sigma = t.value;
          w.tau_s = t.tau_s;
          break;
        case solver::NoiseKind::kFlicker:
          w.kind = solver::WanderKind::kFlicker;
          w.flicker_b = t.value;
          w.tau_min_s = band.tau_min_s;
          w.tau_max_s = band.tau_max_s;
          break;
        case solver::NoiseKind::kRandomWalk:
          w.kind = solver::WanderKind::kRandomWalk;
          w.random_walk_k = t.value;
          break;
        case solver::NoiseKind::kWhite:
        case solver::NoiseKind::kQuantization:
        case solver::NoiseKind::kDrift:
          continue;
      }
      parts.push_back(w);
    }
    solver::WanderModel& w = out.wander[c];
    if (parts.size() == 1) {
      w = parts.front();
    } else if (parts.size() > 1) {
      w.kind = solver::WanderKind::kSum;
      w.parts = std::move(parts);
    }
  }
  return out;
}

solver::KnownWander noise_run_wander(store::Database& db, std::int64_t noise_run,
                                     const std::string& device, const solver::RunData& run) {
  solver::RunNoiseOptions options;
  options.device = device;
  const solver::RunNoise noise = solver::analyse_run_noise(db, noise_run, options);
  // A wander is the unit's own: where both runs name their unit, they must name the same.
  store::RunStore runs(db);
  const solver::RunSetup setup =
      solver::run_setup(runs.load_run(noise_run), noise_run, noise.device);
  if (!setup.imu_serial.empty() && !run.setup.imu_serial.empty() &&
      setup.imu_serial != run.setup.imu_serial) {
    throw core::InputError(
        fmt::format("noise run {}", noise_run),
        fmt::format("its unit is serial {}, run {}'s is {}: a wander is the unit's own",
                    setup.imu_serial, run.setup.run, run.setup.imu_serial));
  }
  const std::vector<solver::ChannelModelFigures> models = solver::channel_noise_models(db, noise);
  const std::string source =
      fmt::format("static run {} (the composite noise model of its step {}, {:.1f} h at {:.0f} Hz)",
                  noise_run, noise.step, noise.duration_s / 3600.0, noise.sample_rate_hz);
  try {
    return wander_from_models(models, flicker_band_of(run), source);
  } catch (const core::InputError& e) {
    throw core::InputError(fmt::format("noise run {}", noise_run), e.what());
  }
}

}  // namespace calstand::analysis

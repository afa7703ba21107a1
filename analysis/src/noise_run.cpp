#include "analysis/noise_run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.hpp"
#include "noise/run_noise.hpp"
#include "solver/noise_estimate.hpp"
#include "solver/octave_allan.hpp"
#include "solver/run_setup.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {
namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// The run's typical step length [s]: the median first-to-last-sample span of its steps.
double typical_step_s(const solver::RunData& run) {
  std::vector<double> durations;
  for (const store::StepData& step : run.steps) {
    if (step.samples.size() > 1) {
      durations.push_back(step.samples.back().receive_time_s - step.samples.front().receive_time_s);
    }
  }
  return median(durations);
}

/// The capture `step` of `device` in `run` as it streams from the store, block-averaged to at
/// most kMaxStaticSamples samples: a day at rest at 1 kHz (86 M samples, 10 GB as samples and
/// table rows) would not fit in memory whole, and the segment means the wander is measured on
/// are the same from block means (their white part then per block, consistently). The table
/// state is a constant at rest, and any constant serves a model of biases alone (the reference
/// it sets is a constant the biases take): zero.
store::StepData averaged_capture(store::Database& db, std::int64_t run, std::size_t step,
                                 const std::string& device) {
  std::int64_t count = 0;
  for (const store::StepMean& m : store::read_step_means(db, run)) {
    if (m.step_index == step && m.device == device) count = m.count;
  }
  const auto block = static_cast<std::size_t>(
      std::max<std::int64_t>(1, (count + kMaxStaticSamples - 1) / kMaxStaticSamples));
  store::StepData out;
  for (const store::StepRecord& r : store::RunStore(db).load_steps(run)) {
    if (r.index == step) out.step = r;
  }
  core::ImuSample sum;
  std::size_t in_block = 0;
  const auto flush = [&] {
    if (in_block == 0) return;
    const double n = static_cast<double>(in_block);
    core::ImuSample mean = sum;
    mean.device_time_s /= n;
    mean.receive_time_s /= n;
    mean.gyro_dps /= n;
    mean.accel_mps2 /= n;
    mean.temperature_c /= n;
    out.samples.push_back(mean);
    out.table.push_back(store::TableSample{0.0, 0.0, 0.0, 0.0});
    sum = core::ImuSample{};
    in_block = 0;
  };
  store::for_each_chunk(db, run, step, device,
                        [&](const store::ChunkInfo&, std::span<const core::ImuSample> chunk) {
                          for (const core::ImuSample& x : chunk) {
                            if (in_block == 0) sum.sequence = x.sequence;
                            sum.device_time_s += x.device_time_s;
                            sum.receive_time_s += x.receive_time_s;
                            sum.gyro_dps += x.gyro_dps;
                            sum.accel_mps2 += x.accel_mps2;
                            sum.temperature_c += x.temperature_c;
                            if (++in_block == block) flush();
                          }
                        });
  flush();
  return out;
}

}  // namespace

solver::RunData segment_record(const solver::RunData& record, double segment_s) {
  if (record.steps.empty()) throw core::InputError("static record", "has no step");
  const store::StepData& capture = record.steps.front();
  solver::RunData out;
  out.setup = record.setup;
  if (capture.samples.empty() || !(segment_s > 0.0)) return out;
  const bool with_table = capture.table.size() == capture.samples.size();
  const double t0 = capture.samples.front().receive_time_s;
  std::size_t begin = 0;
  for (std::size_t k = 1; begin < capture.samples.size(); ++k) {
    const double end_s = t0 + segment_s * static_cast<double>(k);
    std::size_t end = begin;
    while (end < capture.samples.size() && capture.samples[end].receive_time_s < end_s) ++end;
    // A last piece shorter than a segment would weigh as a full one: left out.
    if (end == capture.samples.size() &&
        capture.samples.back().receive_time_s - capture.samples[begin].receive_time_s <
            0.9 * segment_s) {
      break;
    }
    store::StepData segment;
    segment.step = capture.step;
    segment.step.index = out.steps.size();
    segment.step.label = fmt::format("{} segment {}", capture.step.label, out.steps.size() + 1);
    segment.samples.assign(capture.samples.begin() + static_cast<std::ptrdiff_t>(begin),
                           capture.samples.begin() + static_cast<std::ptrdiff_t>(end));
    if (with_table) {
      segment.table.assign(capture.table.begin() + static_cast<std::ptrdiff_t>(begin),
                           capture.table.begin() + static_cast<std::ptrdiff_t>(end));
    }
    if (segment.samples.size() > 1) out.steps.push_back(std::move(segment));
    begin = end;
  }
  return out;
}

solver::KnownWander wander_of_static_record(const solver::RunData& record,
                                            const solver::RunData& run, const std::string& source) {
  if (record.steps.empty() || record.steps.front().samples.size() < 2) {
    throw core::InputError(source, "holds no capture to measure a wander on");
  }
  const auto& samples = record.steps.front().samples;
  const double record_s = samples.back().receive_time_s - samples.front().receive_time_s;
  const double step_s = typical_step_s(run);
  if (!(step_s > 0.0)) {
    throw core::InputError("run", "has no step with two samples: no step length to weigh at");
  }
  const double segment_s = std::max(step_s, record_s / static_cast<double>(kMaxStaticSegments));
  const solver::RunData segments = segment_record(record, segment_s);
  if (segments.steps.size() < kMinStaticSegments) {
    throw core::InputError(
        source, fmt::format("its capture of {:.0f} s gives {} segments of the run's {:.0f} s steps "
                            "where at least {} are needed to tell a wander ({:.0f} s or more)",
                            record_s, segments.steps.size(), step_s, kMinStaticSegments,
                            static_cast<double>(kMinStaticSegments) * step_s));
  }
  // At rest a bias is all there is to fit: the Earth rate and gravity are constants it takes.
  const solver::Model biases = solver::Model::parse("gyro_bias,accel_bias");
  // The best process by the likelihood: no slow effect competes with it at rest.
  solver::NoiseEstimateOptions options;
  options.prefer_flicker = false;
  const solver::StepNoise noise = solver::estimate_step_noise(
      solver::summarize_steps(segments, biases), biases, solver::SensorRows::kBoth, options);
  solver::KnownWander out;
  out.source = fmt::format("{}: restricted likelihood of {} means of {:.0f} s over {:.1f} h",
                           source, segments.steps.size(), segment_s, record_s / 3600.0);
  for (std::size_t c = 0; c < out.wander.size(); ++c) {
    const solver::ChannelStepNoise& ch = noise.channels[c];
    // A flicker is spread over the run's own band where the solver weighs it.
    if (ch.determined) out.wander[c] = ch.wander;
  }
  return out;
}

solver::KnownWander noise_run_wander(store::Database& db, std::int64_t noise_run,
                                     const std::string& device, const solver::RunData& run) {
  const std::string where = fmt::format("noise run {}", noise_run);
  const std::size_t step = solver::choose_noise_step(db, noise_run, std::nullopt);
  const std::string chosen = solver::noise_device(db, noise_run, device);
  const store::RunRecord stored = store::RunStore(db).load_run(noise_run);
  // A record at rest needs no site or table (one imported without them serves as well): the
  // biases its segments are fitted with take gravity and the Earth rate whatever they are.
  solver::RunData record;
  record.setup.run = noise_run;
  record.setup.device = chosen;
  const solver::UnitIdentity unit = solver::unit_identity(stored, chosen);
  record.setup.imu_model = unit.model;
  record.setup.imu_serial = unit.serial;
  // A wander is the unit's own: where both runs name their unit, they must name the same.
  if (!record.setup.imu_serial.empty() && !run.setup.imu_serial.empty() &&
      record.setup.imu_serial != run.setup.imu_serial) {
    throw core::InputError(
        where, fmt::format("its unit is serial {}, run {}'s is {}: a wander is the "
                           "unit's own",
                           record.setup.imu_serial, run.setup.run, run.setup.imu_serial));
  }
  record.steps.push_back(averaged_capture(db, noise_run, step, chosen));
  if (record.steps.front().samples.empty()) {
    throw core::InputError(where, fmt::format("step {} holds no samples of {}", step, chosen));
  }
  const std::string label = record.steps.front().step.label;
  try {
    return wander_of_static_record(
        record, run, fmt::format("static run {} step {} ({})", noise_run, step, label));
  } catch (const core::InputError& e) {
    throw core::InputError(where, e.what());
  }
}

void throw_noise_run_on_table_free(std::int64_t run) {
  throw core::InputError("--noise-run",
                         fmt::format("run {} was recorded without a table: its poses are weighed "
                                     "by their own noise (the pose means' wander), not a static "
                                     "run's",
                                     run));
}

}  // namespace calstand::analysis

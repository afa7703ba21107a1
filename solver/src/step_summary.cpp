#include "solver/step_summary.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"
#include "solver/step_regressors.hpp"
#include "store/run_store.hpp"

namespace calstand::solver {
namespace {

// Blocks per step for the batch-means estimate of the step mean's variance: enough blocks for a
// usable estimate (9 degrees of freedom per step, pooled over steps), long enough blocks that
// the output filter's short correlation does not matter.
constexpr int kBatchBlocks = 10;
constexpr int kMinSamplesPerBlock = 4;
// A table axis slower than this is at rest (encoder noise at rest is far below it) [deg/s].
constexpr double kStaticRateDps = 1e-3;

bool same_table_state(const store::TableSample& a, const store::TableSample& b) {
  return a.outer_deg == b.outer_deg && a.inner_deg == b.inner_deg &&
         a.outer_rate_dps == b.outer_rate_dps && a.inner_rate_dps == b.inner_rate_dps;
}

}  // namespace

RunData load_run_data(store::Database& db, std::int64_t run, const std::string& device) {
  store::RunStore runs(db);
  const store::RunRecord record = runs.load_run(run);
  const std::string chosen = store::choose_device(db, run, device);
  RunData data;
  data.setup = run_setup(record, run, chosen);
  data.steps = store::read_step_data(db, run, chosen);
  if (data.steps.empty()) {
    throw core::InputError(fmt::format("run {}", run), "has no completed steps with samples");
  }
  return data;
}

std::vector<StepSummary> summarize_steps(const RunData& data, const Model& model) {
  const SignalBuilder build(data.setup, model.earth_rate());
  // The run's first sample, wherever it is (imported steps need not be in time order): every
  // step's start and end are then non-negative, as the noise model's random walk needs.
  double run_start_s = data.steps.front().samples.front().receive_time_s;
  for (const store::StepData& step : data.steps) {
    for (const core::ImuSample& sample : step.samples)
      run_start_s = std::min(run_start_s, sample.receive_time_s);
  }
  const auto P = static_cast<Eigen::Index>(model.size());
  // The regressors' step means from sums of the few signal products they are made of, not from
  // every parameter's regressor at every sample (step_regressors.hpp).
  StepRegressorSums regressor_sums(model);
  std::vector<StepSummary> out;
  out.reserve(data.steps.size());
  for (const store::StepData& step : data.steps) {
    const std::size_t n = step.samples.size();
    const std::vector<double> temperature_rates = step_temperature_rates(step.samples);
    StepSummary s;
    s.index = step.step.index;
    s.label = step.step.label;
    s.count = static_cast<std::int64_t>(n);
    s.duration_s = step.samples.back().receive_time_s - step.samples.front().receive_time_s;
    s.start_s = step.samples.front().receive_time_s - run_start_s;
    s.end_s = step.samples.back().receive_time_s - run_start_s;
    s.regressors.resize(kChannels, P);
    regressor_sums.clear();
    // Block means of measurement - reference for the batch-means variance.
    const int blocks =
        n >= static_cast<std::size_t>(kBatchBlocks * kMinSamplesPerBlock) ? kBatchBlocks : 0;
    std::vector<Vector6d> block_sum(static_cast<std::size_t>(blocks), Vector6d::Zero());
    std::vector<double> block_count(static_cast<std::size_t>(blocks), 0.0);
    // Sample i belongs to block i * blocks / n, which reaches block b + 1 at the first i with
    // i * blocks >= (b + 1) n: found once per block instead of a division per sample.
    std::size_t block = 0;
    const auto block_start = [&](std::size_t b) {
      return (b * n + static_cast<std::size_t>(blocks) - 1) / static_cast<std::size_t>(blocks);
    };
    std::size_t next_block_start = blocks > 0 ? block_start(1) : n;
    OctaveAllanSums octaves(octaves_for(s.count));
    double max_rate = 0.0;
    Signals sig;
    for (std::size_t i = 0; i < n; ++i) {
      const core::ImuSample& sample = step.samples[i];
      const store::TableSample& table = step.table[i];
      max_rate =
          std::max({max_rate, std::abs(table.outer_rate_dps), std::abs(table.inner_rate_dps)});
      const double elapsed_s = sample.receive_time_s - run_start_s;
      // A static step's samples share one table state: its rotations are computed once.
      if (i > 0 && same_table_state(table, step.table[i - 1])) {
        build.advance_at_same_table(sig, sample, temperature_rates[i], elapsed_s);
      } else {
        sig = build(sample, table, temperature_rates[i], elapsed_s);
      }
      Vector6d meas;
      meas << sample.gyro_dps, sample.accel_mps2;
      const Vector6d ref = model.reference(sig);
      s.measured += meas;
      s.reference += ref;
      regressor_sums.add(sig);
      const auto values = signal_values(sig);
      for (std::size_t k = 0; k < kSignalCount; ++k) {
        s.signals[k] += values[k];
        s.signals_sq[k] += values[k] * values[k];
        s.signals_abs[k] += std::abs(values[k]);
      }
      octaves.add(meas - ref);
      if (blocks > 0) {
        while (i >= next_block_start) next_block_start = block_start(++block + 1);
        block_sum[block] += meas - ref;
        block_count[block] += 1.0;
      }
    }
    const double inv_n = 1.0 / static_cast<double>(n);
    s.measured *= inv_n;
    s.reference *= inv_n;
    regressor_sums.mean(s.count, s.regressors);
    for (std::size_t k = 0; k < kSignalCount; ++k) {
      s.signals[k] *= inv_n;
      s.signals_sq[k] *= inv_n;
      s.signals_abs[k] *= inv_n;
    }
    s.is_static = max_rate < kStaticRateDps;
    s.octave_allan = octaves.result();
    if (blocks > 1) {
      // Allan variance of the block means (half the mean squared difference of neighbours)
      // estimates one block mean's variance without being inflated by a slow drift; the step
      // mean averages `blocks` of them.
      Vector6d avar = Vector6d::Zero();
      for (int b = 0; b + 1 < blocks; ++b) {
        const Vector6d d =
            block_sum[static_cast<std::size_t>(b + 1)] /
                block_count[static_cast<std::size_t>(b + 1)] -
            block_sum[static_cast<std::size_t>(b)] / block_count[static_cast<std::size_t>(b)];
        avar += 0.5 * d.cwiseProduct(d);
      }
      avar /= static_cast<double>(blocks - 1);
      s.mean_variance = avar / static_cast<double>(blocks);
    }
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<StepSummary> select_parameters(const std::vector<StepSummary>& steps,
                                           const Model& superset, const Model& subset) {
  if (superset.earth_rate() != subset.earth_rate()) {
    throw std::invalid_argument("select_parameters: the models disagree on earth_rate");
  }
  std::vector<Eigen::Index> columns;
  for (const auto& p : subset.parameters()) {
    const auto& all = superset.parameters();
    const auto it = std::find_if(all.begin(), all.end(),
                                 [&](const ParameterInfo& q) { return q.name == p.name; });
    if (it == all.end()) {
      throw std::invalid_argument("select_parameters: " + p.name + " is not in the superset");
    }
    columns.push_back(it - all.begin());
  }
  std::vector<StepSummary> out;
  out.reserve(steps.size());
  for (const StepSummary& s : steps) {
    StepSummary t = s;
    t.regressors.resize(kChannels, static_cast<Eigen::Index>(columns.size()));
    for (std::size_t j = 0; j < columns.size(); ++j) {
      t.regressors.col(static_cast<Eigen::Index>(j)) = s.regressors.col(columns[j]);
    }
    out.push_back(std::move(t));
  }
  return out;
}

NoiseFloor measure_noise_floor(const std::vector<StepSummary>& steps) {
  NoiseFloor floor;
  for (const bool static_only : {true, false}) {
    floor.density.setZero();
    floor.steps_used = 0;
    std::vector<OctaveAllan> pooled;
    std::vector<std::int64_t> counts;
    for (const StepSummary& s : steps) {
      if ((static_only && !s.is_static) || std::isnan(s.mean_variance[0])) continue;
      floor.density += s.mean_variance * static_cast<double>(s.count);
      ++floor.steps_used;
      counts.push_back(s.count);
      if (pooled.size() < s.octave_allan.size()) pooled.resize(s.octave_allan.size());
      for (std::size_t j = 0; j < s.octave_allan.size(); ++j) {
        pooled[j].half_squared_differences += s.octave_allan[j].half_squared_differences;
        pooled[j].differences += s.octave_allan[j].differences;
      }
    }
    if (floor.steps_used > 0) {
      floor.density /= static_cast<double>(floor.steps_used);
      floor.batch_density = floor.density;
      floor.from_static_steps = static_only;
      // The white part of the steps' Allan curve, up to the blocks of a typical step's batch
      // means: the batch means' own figure holds the wander at that block length too (a
      // flicker floor, a Gauss-Markov bias), which the wander model then counts again.
      std::nth_element(counts.begin(), counts.begin() + counts.size() / 2, counts.end());
      const std::int64_t typical_block = counts[counts.size() / 2] / kBatchBlocks;
      if (const std::optional<Vector6d> white =
              white_variance_from_octaves(pooled, typical_block)) {
        floor.density = *white;
        floor.from_octave_fit = true;
      }
      // A channel with no scatter at all (a constant column in imported data) would get an
      // infinite weight; give it the smallest non-zero floor of its sensor instead.
      for (Vector6d* figure : {&floor.density, &floor.batch_density}) {
        for (int sensor = 0; sensor < 2; ++sensor) {
          double smallest = std::numeric_limits<double>::infinity();
          for (int i = 0; i < 3; ++i) {
            if ((*figure)[3 * sensor + i] > 0.0)
              smallest = std::min(smallest, (*figure)[3 * sensor + i]);
          }
          for (int i = 0; i < 3; ++i) {
            if (!((*figure)[3 * sensor + i] > 0.0)) {
              (*figure)[3 * sensor + i] = std::isfinite(smallest) ? smallest : 1e-30;
            }
          }
        }
      }
      return floor;
    }
  }
  throw core::InputError("noise floor",
                         fmt::format("no step has the {} samples needed to measure the scatter "
                                     "inside a step",
                                     kBatchBlocks * kMinSamplesPerBlock));
}

}  // namespace calstand::solver

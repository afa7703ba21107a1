// The whole diagnosis with the search for custom terms (issue 13 target: under 0.5 s) on the
// 100k-sample campaign of fit_bench.cpp: with an effect outside the catalogue (gz following
// force_z^2), where the search runs and confirms its suggestions through fit_run (each one a
// pass over the samples with the noise superset); on the clean campaign with the search forced,
// where every form is screened and none survives; and without the search.
#include <benchmark/benchmark.h>

#include "../tests/unit/solver/sim_run.hpp"
#include "solver/diagnose.hpp"

namespace {

using namespace calstand;
using solver::testing::SimStep;

constexpr const char* kBase =
    "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,accel_misalignment";

solver::RunData campaign_100k(bool with_effect) {
  sim::ImuTruth truth = solver::testing::white_noise_truth(2e-3, 5e-4, 200.0);
  std::vector<SimStep> steps;
  for (double temp : {-20.0, 25.0, 70.0}) {
    for (auto s : solver::testing::six_positions(temp, 20.0)) steps.push_back(s);
    for (auto s : solver::testing::rate_steps({30.0, 90.0}, temp, 4.0)) steps.push_back(s);
  }
  solver::RunData data = solver::testing::simulate_run(truth, steps, 1);
  if (with_effect) {
    const solver::SignalBuilder build(data.setup, true);
    for (auto& step : data.steps) {
      for (std::size_t i = 0; i < step.samples.size(); ++i) {
        const double fz = build(step.samples[i], step.table[i], 0.0, 0.0).force_mps2.z();
        step.samples[i].gyro_dps.z() += 1e-4 * fz * fz;
      }
    }
  }
  return data;
}

void run(benchmark::State& state, const solver::RunData& data, solver::CustomSearch search,
         std::size_t max_suggestions = solver::SuggestOptions{}.max_suggestions) {
  const solver::Model base = solver::Model::parse(kBase);
  solver::DiagnoseOptions options;
  options.custom_search = search;
  options.suggest.max_suggestions = max_suggestions;
  solver::Diagnosis d;
  for (auto _ : state) {
    d = solver::diagnose(data, base, {}, options);
    benchmark::DoNotOptimize(d.suggestions.size());
  }
  state.counters["searched"] = d.custom_searched ? 1.0 : 0.0;
  state.counters["forms"] = d.custom_forms_tried;
  state.counters["suggestions"] = static_cast<double>(d.suggestions.size());
}

void BM_DiagnoseWithACustomEffect(benchmark::State& state) {
  static const solver::RunData data = campaign_100k(true);
  run(state, data, solver::CustomSearch::kWhenUnexplained);
}
BENCHMARK(BM_DiagnoseWithACustomEffect)->Unit(benchmark::kMillisecond);

// The same confirming only the best suggestion: each confirmation is a fit_run.
void BM_DiagnoseWithACustomEffectBestOnly(benchmark::State& state) {
  static const solver::RunData data = campaign_100k(true);
  run(state, data, solver::CustomSearch::kWhenUnexplained, 1);
}
BENCHMARK(BM_DiagnoseWithACustomEffectBestOnly)->Unit(benchmark::kMillisecond);

void BM_DiagnoseSearchForcedOnACleanRun(benchmark::State& state) {
  static const solver::RunData data = campaign_100k(false);
  run(state, data, solver::CustomSearch::kAlways);
}
BENCHMARK(BM_DiagnoseSearchForcedOnACleanRun)->Unit(benchmark::kMillisecond);

void BM_DiagnoseNoSearch(benchmark::State& state) {
  static const solver::RunData data = campaign_100k(false);
  run(state, data, solver::CustomSearch::kNever);
}
BENCHMARK(BM_DiagnoseNoSearch)->Unit(benchmark::kMillisecond);

void BM_DiagnoseDefault(benchmark::State& state) {
  static const solver::RunData data = campaign_100k(false);
  run(state, data, solver::CustomSearch::kWhenUnexplained);
}
BENCHMARK(BM_DiagnoseDefault)->Unit(benchmark::kMillisecond);

}  // namespace

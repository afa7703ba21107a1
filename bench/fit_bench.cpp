// Fit plus a 13-candidate diagnosis on a 100k-sample campaign (issue 4 target: under 0.2 s):
// one pass over the samples builds the step summaries of every catalogue term, then the base
// model is fitted and refitted with each candidate term added.
#include <benchmark/benchmark.h>

#include "../tests/unit/solver/sim_run.hpp"
#include "analysis/run_model.hpp"
#include "solver/diagnose.hpp"
#include "solver/fit.hpp"

namespace {

using namespace calstand;
using solver::testing::SimStep;

// The base model of both benchmarks is the default model of `calstand fit`.
constexpr const char* kBase = analysis::kDefaultModel;

const solver::RunData& campaign_100k() {
  static const solver::RunData data = [] {
    sim::ImuTruth truth = solver::testing::white_noise_truth(2e-3, 5e-4, 200.0);
    std::vector<SimStep> steps;
    for (double temp : {-20.0, 25.0, 70.0}) {
      for (auto s : solver::testing::six_positions(temp, 20.0)) steps.push_back(s);
      for (auto s : solver::testing::rate_steps({30.0, 90.0}, temp, 4.0)) steps.push_back(s);
    }
    return solver::testing::simulate_run(truth, steps, 1);
  }();
  return data;
}

std::size_t sample_count(const solver::RunData& d) {
  std::size_t n = 0;
  for (const auto& s : d.steps) n += s.samples.size();
  return n;
}

void BM_FitAndThirteenCandidates(benchmark::State& state) {
  const solver::RunData& data = campaign_100k();
  const solver::Model base = solver::Model::parse(kBase);
  std::vector<solver::Model> candidates;
  solver::Model superset = base;
  for (const auto& term : core::error_term_catalogue()) {
    if (base.find(term.name)) continue;
    candidates.push_back(base.with_term(term));
    superset = superset.with_term(term);
  }
  // Second orders of the temperature polynomials: 13 candidates in all.
  for (const char* name : {"gyro_temp_bias", "accel_temp_bias"}) {
    candidates.push_back(base.with_term(*core::find_error_term(name), 2));
    superset = superset.with_term(*core::find_error_term(name), 2);
  }
  for (auto _ : state) {
    const auto steps = solver::summarize_steps(data, superset);
    const solver::NoiseFloor floor = solver::measure_noise_floor(steps);
    auto fit = solver::fit_model(solver::select_parameters(steps, superset, base), base, floor);
    benchmark::DoNotOptimize(fit.chi2);
    for (const auto& c : candidates) {
      auto refit = solver::fit_model(solver::select_parameters(steps, superset, c), c, floor);
      benchmark::DoNotOptimize(refit.chi2);
    }
  }
  state.counters["samples"] = static_cast<double>(sample_count(data));
  state.counters["candidates"] = static_cast<double>(candidates.size());
}
BENCHMARK(BM_FitAndThirteenCandidates)->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

// The whole `calstand diagnose` computation on the same campaign (issue 5 target: under 0.5 s):
// the base fit, every candidate term, groups and signal correlations.
void BM_Diagnose(benchmark::State& state) {
  const solver::RunData& data = campaign_100k();
  const solver::Model base = solver::Model::parse(kBase);
  for (auto _ : state) {
    const solver::Diagnosis d = solver::diagnose(data, base);
    benchmark::DoNotOptimize(d.candidates.size());
  }
  state.counters["samples"] = static_cast<double>(sample_count(data));
}
BENCHMARK(BM_Diagnose)->Unit(benchmark::kMillisecond);

}  // namespace

// Overlapping Allan deviation at octave taus of 12 h of 125 Hz data (5.4 million samples, the
// seed notes' STIM300 record). Target (issue 4): under 0.1 s on one core.
//
//   build/bench/calstand_bench --benchmark_filter=Allan
//
// OverlappingAllanOctave is the whole allan() call as the CLI makes it: mean removal, the
// compensated cumulative sum, 22 taus and their degrees of freedom and chi-square intervals.
// The Curve variant leaves the intervals out, to show what the sums alone cost.
// DeviationStreamOctave is the same curve from solver::DeviationStream, the record pushed in
// blocks of 65,536 (the constant-memory path of a day at 1 kHz, docs/noise-id.md).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <span>
#include <vector>

#include "noise/allan.hpp"
#include "noise/deviation_stream.hpp"
#include "sim/noise.hpp"

namespace calstand::solver {
namespace {

constexpr double kRateHz = 125.0;
constexpr std::size_t kSamples = static_cast<std::size_t>(12 * 3600 * kRateHz);

// Gyro-like data [deg/s]: white noise (0.15 deg/sqrt(h)) plus a rate random walk, once.
const std::vector<double>& data() {
  static const std::vector<double> y = [] {
    sim::WhiteNoise white(0.15 / 60.0, kRateHz, 1);
    sim::RandomWalk walk(1e-5, 1.0 / kRateHz, 2);
    std::vector<double> v(kSamples);
    for (double& x : v) x = white.next() + walk.next();
    return v;
  }();
  return y;
}

void run(benchmark::State& state, bool intervals) {
  const std::vector<double>& y = data();
  AllanOptions options;
  options.intervals = intervals;
  for (auto _ : state) {
    AllanResult r = allan(y, kRateHz, options);
    benchmark::DoNotOptimize(r.points.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(y.size()));
  state.counters["taus"] = static_cast<double>(allan(y, kRateHz, options).points.size());
}

void BM_OverlappingAllanOctave(benchmark::State& state) { run(state, true); }
void BM_OverlappingAllanOctaveCurve(benchmark::State& state) { run(state, false); }
BENCHMARK(BM_OverlappingAllanOctave)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OverlappingAllanOctaveCurve)->Unit(benchmark::kMillisecond);

void BM_DeviationStreamOctave(benchmark::State& state) {
  const std::vector<double>& y = data();
  const std::span<const double> all(y);
  for (auto _ : state) {
    DeviationStream stream({AllanKind::kAllan});
    for (std::size_t i = 0; i < y.size(); i += 65536) {
      stream.push(all.subspan(i, std::min<std::size_t>(65536, y.size() - i)));
    }
    AllanResult r = stream.result(kRateHz, {});
    benchmark::DoNotOptimize(r.points.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(y.size()));
}
BENCHMARK(BM_DeviationStreamOctave)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace calstand::solver

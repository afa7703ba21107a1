// Simulator throughput: how many IMU samples per second one core produces, and what that means
// as a real-time factor for one IMU at 1 kHz. Target (issue 2): 2000x real time or better.
//
//   build/bench/calstand_bench --benchmark_filter=World
//
// The world benchmarks run the whole physics loop (table servo, chamber, IMU truth terms,
// every noise process of the spec sheet, output filter) with the table turning, which is the
// expensive case (rates, lever arm kinematics and rotations change every sample).
#include <benchmark/benchmark.h>

#include "sim/imu_truth.hpp"
#include "sim/sim_world.hpp"
#include "sim/spec_sheet.hpp"

namespace calstand::sim {
namespace {

// The default station with its IMU replaced by one drawn from `model`, output at `rate_hz`.
core::StationConfig station_with(const char* model, double rate_hz) {
  core::StationConfig c = default_station();
  ImuTruth truth = truth_from_spec(*builtin_spec(model), model, 1);
  truth.sample_rate_hz = rate_hz;
  if (truth.gyro_bandwidth_hz >= rate_hz / 2.0) truth.gyro_bandwidth_hz = 0.0;
  if (truth.accel_bandwidth_hz >= rate_hz / 2.0) truth.accel_bandwidth_hz = 0.0;
  truth.accel_lever_arm = {0.02, -0.01, 0.03};  // exercise the lever-arm kinematics too
  c.imus[0].model.clear();
  c.imus[0].truth = imu_truth_to_json(truth);
  return c;
}

void run_world(benchmark::State& state, const char* model) {
  SimWorld world(station_with(model, 1000.0));
  world.table().outer().command_rate(20.0);
  world.table().inner().command_rate(-90.0);
  std::size_t samples = 0;
  world.set_sample_sink([&](std::size_t, const core::ImuSample&) { ++samples; });
  const double chunk_s = 1.0;  // one simulated second per iteration
  for (auto _ : state) {
    world.advance(chunk_s);
  }
  state.SetItemsProcessed(static_cast<int64_t>(samples));
  // Simulated seconds per wall second for a 1 kHz IMU: samples/s divided by 1000.
  state.counters["realtime_factor"] =
      benchmark::Counter(static_cast<double>(samples) / 1000.0, benchmark::Counter::kIsRate);
}

void BM_WorldLn200At1kHz(benchmark::State& state) { run_world(state, "ln200"); }
void BM_WorldAdis16488At1kHz(benchmark::State& state) { run_world(state, "adis16488"); }
BENCHMARK(BM_WorldLn200At1kHz)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_WorldAdis16488At1kHz)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The IMU model alone (truth terms + noise + filter), without the table and world loop.
void BM_ImuSampleLn200(benchmark::State& state) {
  ImuTruth truth = truth_from_spec(*builtin_spec("ln200"), "ln200", 1);
  truth.sample_rate_hz = 1000.0;
  ImuSim imu(truth, {}, default_station().site, Eigen::Vector2d::Zero(), 1);
  imu.power_on(0.0);
  TableKinematics k;
  k.inner_rate_dps = 90.0;
  double t = 0.0;
  for (auto _ : state) {
    k.inner_deg += 0.09;
    benchmark::DoNotOptimize(imu.sample(t, k, 25.0));
    t += 1e-3;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ImuSampleLn200);

}  // namespace
}  // namespace calstand::sim

// A station capturing 8 IMUs of mixed wire formats at their top rates at once (issue 29): the
// protocol simulator serves each simulated unit on its own pseudo-terminal in its format, and
// the real serial driver (configuration dialogue, decoder, clock estimate) reads each; the
// figures say whether any sample is lost on this machine. A plain program:
//
//   calstand_imu_capture_bench [SECONDS=30]
//
// Prints per IMU: format, rate, samples received and expected (from the unit's own clock over
// what was received), sequence gaps, checksum errors, garbage, and the frames the simulator had
// to drop; exits 1 on any loss.
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "core/clock.hpp"
#include "drivers/protocol_simulator.hpp"
#include "drivers/serial_imu.hpp"
#include "sim/imu_truth.hpp"
#include "sim/sim_world.hpp"

namespace {

using namespace calstand;

struct Unit {
  const char* format;
  double rate_hz;  ///< the top rate of the unit's format [Hz]
};

// Xsens MTi at 2 kHz, VectorNav at its 800 Hz IMU rate, Epson at 2 kHz, STIM300 at 2 kHz.
constexpr Unit kUnits[] = {{"xsens", 2000.0},    {"xsens", 2000.0},  {"vectornav", 800.0},
                           {"vectornav", 800.0}, {"epson", 2000.0},  {"epson", 2000.0},
                           {"stim300", 2000.0},  {"stim300", 2000.0}};

core::StationConfig eight_imu_station() {
  core::StationConfig config = sim::load_station_or_default("");
  const core::ImuConfig model = config.imus.at(0);
  config.imus.clear();
  for (std::size_t i = 0; i < std::size(kUnits); ++i) {
    core::ImuConfig imu = model;
    imu.name = fmt::format("imu{}-{}", i, kUnits[i].format);
    sim::ImuTruth truth = sim::resolve_imu_truth(model, config.seed, i);
    truth.sample_rate_hz = kUnits[i].rate_hz;
    truth.gyro_bandwidth_hz = 0.0;  // the sheet's filter was drawn for its own rate
    truth.accel_bandwidth_hz = 0.0;
    imu.model.clear();
    imu.spec_file.clear();
    imu.truth_file.clear();
    imu.truth = sim::imu_truth_to_json(truth);
    config.imus.push_back(imu);
  }
  return config;
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 30.0;
  const core::StationConfig config = eight_imu_station();
  drivers::ProtocolSimOptions options;
  options.f4_rtu = false;
  for (std::size_t i = 0; i < std::size(kUnits); ++i) {
    options.imu_formats[config.imus[i].name] = kUnits[i].format;
  }
  drivers::ProtocolSimulator sim(config, options);
  sim.start();
  const core::StationConfig client = sim.client_station();
  core::SteadyClock clock;
  std::vector<std::unique_ptr<drivers::Imu>> imus;
  for (std::size_t i = 0; i < client.imus.size(); ++i) {
    imus.push_back(
        drivers::make_serial_imu(client.imus[i], clock, fmt::format("imus[{}].connection", i)));
    if (auto r = imus.back()->configure(); !r) {
      fmt::print(stderr, "{}: {}\n", client.imus[i].name, r.message);
      return 2;
    }
    if (auto r = imus.back()->activate(); !r) {
      fmt::print(stderr, "{}: {}\n", client.imus[i].name, r.message);
      return 2;
    }
  }
  std::vector<std::vector<core::ImuSample>> received(imus.size());
  const auto start = std::chrono::steady_clock::now();
  const auto end = start + std::chrono::duration<double>(seconds);
  // Drain as the engine does: every 10 ms.
  while (std::chrono::steady_clock::now() < end) {
    for (std::size_t i = 0; i < imus.size(); ++i) {
      auto got = imus[i]->poll();
      received[i].insert(received[i].end(), got.begin(), got.end());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  for (auto& imu : imus) imu->deactivate();
  const nlohmann::json stats = sim.statistics();
  sim.stop();

  bool lost = false;
  fmt::print("{:<18} {:>7} {:>10} {:>9} {:>6} {:>6} {:>8} {:>8}\n", "imu", "rate Hz", "samples",
             "expected", "gaps", "crc", "garbage", "sim drop");
  for (std::size_t i = 0; i < imus.size(); ++i) {
    const auto& got = received[i];
    const auto counters = imus[i]->fault_counters();
    auto counter = [&](const char* key) {
      const auto it = counters.find(key);
      return it == counters.end() ? std::uint64_t{0} : it->second;
    };
    // Gaps from the samples themselves, as the store sees them.
    std::uint64_t gaps = 0;
    const std::uint64_t modulus = imus[i]->sequence_modulus();
    for (std::size_t k = 1; k < got.size(); ++k) {
      if (got[k].sequence != (std::uint64_t{got[k - 1].sequence} + 1) % modulus) ++gaps;
    }
    // Expected from the unit's own clock over what was received: every sample between the
    // first and the last (the backlog queued during the dialogues comes first, so the count
    // exceeds seconds x rate).
    const double expected =
        got.empty() ? 0.0
                    : std::round((got.back().device_time_s - got.front().device_time_s) *
                                 kUnits[i].rate_hz) +
                          1.0;
    const std::uint64_t dropped = stats["imus"][i]["frames_dropped"].get<std::uint64_t>();
    const std::uint64_t crc = counter("crc_errors");
    const std::uint64_t garbage = counter("garbage_bytes");
    fmt::print("{:<18} {:>7.0f} {:>10} {:>9.0f} {:>6} {:>6} {:>8} {:>8}\n", client.imus[i].name,
               kUnits[i].rate_hz, got.size(), expected, gaps, crc, garbage, dropped);
    if (gaps + crc + garbage + dropped > 0 || static_cast<double>(got.size()) != expected ||
        static_cast<double>(got.size()) < 0.9 * seconds * kUnits[i].rate_hz) {
      lost = true;
    }
  }
  fmt::print("{}\n", lost ? "LOST SAMPLES" : "0 drops");
  return lost ? 1 : 0;
}

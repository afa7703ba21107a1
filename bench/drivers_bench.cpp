// What the real drivers cost, on loopback against the protocol simulators (no targets in the
// issue; the figures say how much headroom a station has):
//
//   bash scripts/run-bench.sh --benchmark_filter=Driver
//
// DriverImuFrameDecode: the calstand frame decoder alone on a 1 MiB stream (frames/s).
// DriverWireFormatDecode/<format>: each wire format's decoder alone (issue 29) on 100 000 of its
//   device emulator's frames at 2 kHz (800 Hz for VectorNav), configured by its own dialogue,
//   read 4 KiB at a time (samples/s on one core).
// DriverSerialImuThroughPty: frames written on a pseudo-terminal by a device thread, read,
//   decoded and stamped by SerialImu, drained by poll() (sustained frames/s end to end).
// DriverTableReadState: AcutrolTable::read_state() against the command server on TCP loopback
//   (both axes: position, rate and status of each; one call's latency).
// DriverModbusReadField: one Modbus TCP read of the F4T process value (two registers, float)
//   against the chamber server (one request's latency).
#include <benchmark/benchmark.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "core/clock.hpp"
#include "drivers/acutrol_server.hpp"
#include "drivers/acutrol_table.hpp"
#include "drivers/chamber_register_map.hpp"
#include "drivers/emulated_device_link.hpp"
#include "drivers/imu_frame.hpp"
#include "drivers/imu_wire_format.hpp"
#include "drivers/modbus_chamber_options.hpp"
#include "drivers/modbus_chamber_server.hpp"
#include "drivers/modbus_client_link.hpp"
#include "drivers/pseudo_terminal.hpp"
#include "drivers/serial_imu.hpp"
#include "sim/sim_world.hpp"

namespace calstand::drivers {
namespace {

core::ImuSample sample(std::uint32_t i) {
  core::ImuSample s;
  s.sequence = i;
  s.device_time_s = 0.001 * i;
  s.gyro_dps = {0.1, -0.2, 0.3};
  s.accel_mps2 = {0.0, 0.0, 9.81};
  s.temperature_c = 25.0;
  return s;
}

std::vector<std::uint8_t> stream_of(std::size_t frames) {
  std::vector<std::uint8_t> bytes;
  for (std::uint32_t i = 0; i < frames; ++i) {
    const auto f = encode_imu_frame(sample(i));
    bytes.insert(bytes.end(), f.begin(), f.end());
  }
  return bytes;
}

void DriverImuFrameDecode(benchmark::State& state) {
  const auto bytes = stream_of((1u << 20) / imu_frame::kFrameSize);
  std::vector<core::ImuSample> out;
  std::size_t frames = 0;
  for (auto _ : state) {
    CalstandFrameDecoder decoder;
    out.clear();
    // Reads of 4 KiB, as the serial driver does.
    for (std::size_t at = 0; at < bytes.size(); at += 4096) {
      decoder.feed(std::span(bytes).subspan(at, std::min<std::size_t>(4096, bytes.size() - at)),
                   out);
    }
    frames += out.size();
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["frames/s"] =
      benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes.size()));
}
BENCHMARK(DriverImuFrameDecode)->Unit(benchmark::kMillisecond);

void DriverWireFormatDecode(benchmark::State& state) {
  const std::string name = imu_wire_format_names().at(static_cast<std::size_t>(state.range(0)));
  state.SetLabel(name);
  const ImuWireFormat& format = imu_wire_format(name, "format");
  WireFormatSettings settings;
  settings.sample_rate_hz = name == "vectornav" ? 800.0 : 2000.0;
  // The STIM300's dialogue times the unit's stream on the wall clock; this link has none.
  if (name == "stim300") settings.options = {{"rate_check", false}};
  EmulatedDeviceLink link(format.make_emulator({"model", "SN1", "1.0", settings.sample_rate_hz}));
  std::uint32_t streamed = 0;
  link.free_run([&] { return sample(streamed++); });
  std::optional<UnitIdentity> unit;
  if (auto configurator = format.make_configurator(settings)) unit = configurator->configure(link);
  link.free_run({});
  std::vector<std::uint8_t> drained(link.pending());
  link.read(drained, std::chrono::milliseconds(0));
  constexpr std::uint32_t kSamples = 100000;
  for (std::uint32_t i = 0; i < kSamples; ++i) {
    core::ImuSample s = sample(i);
    s.device_time_s = i / settings.sample_rate_hz;
    link.sample(s);
  }
  std::vector<std::uint8_t> bytes(link.pending());
  link.read(bytes, std::chrono::milliseconds(0));
  std::vector<core::ImuSample> out;
  std::size_t samples = 0;
  for (auto _ : state) {
    auto decoder = format.make_decoder(settings);
    if (unit) decoder->identified(*unit);
    out.clear();
    for (std::size_t at = 0; at < bytes.size(); at += 4096) {
      decoder->feed(std::span(bytes).subspan(at, std::min<std::size_t>(4096, bytes.size() - at)),
                    out);
    }
    samples += out.size();
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["samples/s"] =
      benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes.size()));
}
BENCHMARK(DriverWireFormatDecode)->DenseRange(0, 4)->Unit(benchmark::kMillisecond);

void DriverSerialImuThroughPty(benchmark::State& state) {
  constexpr std::size_t kFrames = 20000;
  const auto bytes = stream_of(kFrames);
  std::size_t received = 0;
  for (auto _ : state) {
    PseudoTerminal pty;
    core::SteadyClock clock;
    core::ImuConfig config;
    config.name = "imu0";
    config.backend = "serial";
    config.connection = {{"path", pty.slave_path()}, {"baud", 921600}, {"sample_rate_hz", 1000}};
    SerialImu imu(config, clock, "bench");
    imu.configure();
    imu.activate();
    std::thread device([&] { pty.write(bytes, std::chrono::seconds(30)); });
    std::size_t got = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (got < kFrames && std::chrono::steady_clock::now() < deadline) {
      got += imu.poll().size();
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
    device.join();
    imu.deactivate();
    received += got;
    if (got != kFrames) state.SkipWithError("frames lost on the pseudo-terminal");
  }
  state.counters["frames/s"] =
      benchmark::Counter(static_cast<double>(received), benchmark::Counter::kIsRate);
}
BENCHMARK(DriverSerialImuThroughPty)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

void DriverTableReadState(benchmark::State& state) {
  const auto config = sim::default_station();
  sim::SimWorld world(config);
  std::mutex world_mutex;
  SimTableBackend backend(world, world_mutex);
  AcutrolServer server(backend);
  server.start();
  core::TableConfig table = config.table;
  table.backend = "acutrol";
  table.connection = {{"transport", "tcp"}, {"host", "127.0.0.1"}, {"port", server.port()}};
  core::SteadyClock clock;
  auto driver = make_acutrol_table(table, clock);
  if (!driver->configure()) state.SkipWithError("configure failed");
  for (auto _ : state) benchmark::DoNotOptimize(driver->read_state());
  server.stop();
}
BENCHMARK(DriverTableReadState)->Unit(benchmark::kMicrosecond)->UseRealTime();

void DriverModbusReadField(benchmark::State& state) {
  const auto config = sim::default_station();
  sim::SimWorld world(config);
  std::mutex world_mutex;
  SimChamberBackend backend(world, world_mutex);
  auto server = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
  server->start();
  core::ChamberConfig chamber = config.chamber;
  chamber.backend = "modbus";
  chamber.connection = {
      {"transport", "tcp"}, {"host", "127.0.0.1"}, {"port", server->port()}, {"map", "watlow-f4t"}};
  ModbusClientLink link(ModbusChamberOptions::from_config(chamber));
  if (!link.connect().ok()) state.SkipWithError("connect failed");
  const auto field = watlow_f4t_map().process_value;
  double value = 0.0;
  RegisterWords raw{};
  for (auto _ : state) {
    if (!link.read_field(field, value, raw).ok()) state.SkipWithError("read failed");
    benchmark::DoNotOptimize(value);
  }
  server->stop();
}
BENCHMARK(DriverModbusReadField)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace
}  // namespace calstand::drivers

// libFuzzer target: arbitrary CAN frames (ids, length, payload chosen by the fuzzer) into the
// CanSampleAssembler with the example signal map sim/can/calstand-imu-can.json and variants of
// it (reassembly depth 2 and 3, no device_time, big-endian with a float32 gyro, an extended id),
// and the Xsens MTi-600 DBC layout (sim/can/xsens-mti-600.dbc: samples opened by a frame).
// After every frame each frame fed must be counted exactly once (CanAssemblyCounters), feed()
// must return what it appended, and no delivered sample may hold a NaN or an infinity.
//
// Input: byte 0 picks the map variant, byte 1 the sequence modulus, byte 2 the sample rate;
// then records, each a control byte and its operands:
//   ctl % 8 in 0..3  a frame of the map's id (ctl % 8) % ids, 8 bytes of data; ctl & 8: the
//                    length is the next byte % 16 (lengths over 8 are invalid frames)
//   4                a raw frame: 4-byte can_id (flags included), length byte, 8 data bytes
//   5                a whole sample encoded by encode_sample (sequence byte, 8 values of 2 bytes),
//                    its frames fed in an order from a byte, one possibly left out
//   6                reset()
//   7                a frame of the map's id ctl >> 3 re-using the previous payload (a duplicate)
#include <linux/can.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "drivers/can_sample_assembler.hpp"
#include "drivers/can_signal_map.hpp"

#ifndef CALSTAND_SOURCE_DIR
#error "CALSTAND_SOURCE_DIR must name the source tree (tests/fuzz/CMakeLists.txt sets it)"
#endif

namespace {

using namespace calstand::drivers;
using nlohmann::json;

void check(bool ok) {
  if (!ok) std::abort();
}

std::vector<CanSignalMap> make_maps() {
  std::ifstream in(CALSTAND_SOURCE_DIR "/sim/can/calstand-imu-can.json");
  std::stringstream text;
  text << in.rdbuf();
  const json doc = json::parse(text.str());
  std::vector<CanSignalMap> maps;
  maps.push_back(CanSignalMap::from_json(doc, "example"));
  json depth2 = doc;
  depth2["reassembly_depth"] = 2;
  maps.push_back(CanSignalMap::from_json(depth2, "depth2"));
  json no_time = doc;
  no_time["reassembly_depth"] = 3;
  no_time["signals"].erase("device_time");
  maps.push_back(CanSignalMap::from_json(no_time, "no_time"));
  json big = doc;
  big["byte_order"] = "big";
  big["signals"]["gyro_x"] = {
      {"id", "0x101"}, {"start_bit", 0}, {"length_bits", 32}, {"type", "float"}, {"scale", 1.0}};
  big["signals"]["gyro_y"] = {
      {"id", "0x101"}, {"start_bit", 32}, {"length_bits", 24}, {"type", "signed"}, {"scale", 1e-4}};
  maps.push_back(CanSignalMap::from_json(big, "big"));
  json extended = doc;
  extended["signals"]["temperature"]["extended"] = true;
  maps.push_back(CanSignalMap::from_json(extended, "extended"));
  // A DBC layout: samples opened by a frame, the counter in its own message, status signals.
  std::ifstream station(CALSTAND_SOURCE_DIR "/sim/can/xsens-mti-600-station.json");
  std::stringstream station_text;
  station_text << station.rdbuf();
  const json connection = json::parse(station_text.str())["imus"][0]["connection"];
  maps.push_back(CanSignalMap::from_dbc(CALSTAND_SOURCE_DIR "/sim/can/xsens-mti-600.dbc",
                                        connection, "xsens"));
  return maps;
}

const std::vector<CanSignalMap>& maps() {
  static const std::vector<CanSignalMap> m = make_maps();
  return m;
}

struct Reader {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t at = 0;
  bool more() const { return at < size; }
  std::uint8_t byte() { return at < size ? data[at++] : 0; }
};

bool finite(const calstand::core::ImuSample& s) {
  return std::isfinite(s.device_time_s) && std::isfinite(s.receive_time_s) &&
         s.gyro_dps.allFinite() && s.accel_mps2.allFinite() && std::isfinite(s.temperature_c);
}

void check_counts(const CanSampleAssembler& a) {
  const auto& s = a.stats();
  check(s.frames == s.unknown_ids + s.bad_frames + s.bad_dlc + s.duplicate_frames + s.late_frames +
                        s.frames_used + s.frames_discarded + s.status_frames + a.pending_frames());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in{data, size};
  const CanSignalMap& map = maps()[in.byte() % maps().size()];
  const std::uint8_t modulus_byte = in.byte();
  const std::uint64_t modulus = modulus_byte == 0 ? map.sequence_wrap() : 2 + modulus_byte % 255;
  const double rate_hz = in.byte() * 10.0;  // 0 is refused and replaced
  CanSampleAssembler assembler(map, modulus, rate_hz);
  const std::size_t ids = map.frames.size();

  std::vector<calstand::core::ImuSample> out;
  std::uint64_t frames_fed = 0;
  can_frame last{};
  auto feed = [&](const can_frame& frame) {
    const std::size_t before = out.size();
    const std::size_t n = assembler.feed(frame, out);
    ++frames_fed;
    check(n <= 1 && out.size() == before + n);
    for (std::size_t i = before; i < out.size(); ++i) {
      check(finite(out[i]));
      check(out[i].sequence < modulus);
    }
    check(assembler.stats().frames == frames_fed);
    check_counts(assembler);
    last = frame;
  };

  while (in.more()) {
    const std::uint8_t ctl = in.byte();
    switch (ctl % 8) {
      case 0:
      case 1:
      case 2:
      case 3: {
        can_frame f{};
        f.can_id = map.frames[(ctl % 8) % ids].id;
        f.len = (ctl & 8) ? in.byte() % 16 : 8;
        for (auto& b : f.data) b = in.byte();
        feed(f);
        break;
      }
      case 4: {
        can_frame f{};
        for (int i = 0; i < 4; ++i) f.can_id = (f.can_id << 8) | in.byte();
        f.len = in.byte();
        for (auto& b : f.data) b = in.byte();
        feed(f);
        break;
      }
      case 5: {
        calstand::core::ImuSample s;
        s.sequence = in.byte();
        auto value = [&] {
          const unsigned high = in.byte();
          const unsigned low = in.byte();
          return static_cast<std::int16_t>(high << 8 | low) * 0.05;
        };
        s.gyro_dps = {value(), value(), value()};
        s.accel_mps2 = {value(), value(), value()};
        s.temperature_c = value();
        s.device_time_s = std::abs(value()) * 100.0;
        auto frames = encode_sample(map, s);
        const std::uint8_t order = in.byte();
        std::rotate(frames.begin(), frames.begin() + order % frames.size(), frames.end());
        if (order & 0x80) frames.pop_back();
        for (const auto& f : frames) feed(f);
        break;
      }
      case 6:
        assembler.reset();
        check(assembler.pending_frames() == 0);
        check_counts(assembler);
        break;
      case 7: {
        can_frame f = last;
        f.can_id = map.frames[(ctl >> 3) % ids].id;
        feed(f);
        break;
      }
    }
  }
  check(assembler.stats().samples == out.size());
  const auto named = assembler.counters();  // once: building the map per frame is slow
  check(named.at("frames") == frames_fed && named.at("samples") == out.size());
  return 0;
}

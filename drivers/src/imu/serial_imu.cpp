#include "drivers/serial_imu.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>

#include "core/error.hpp"

namespace calstand::drivers {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;

// The reader wakes at least this often to notice deactivate() [ms].
constexpr auto kReadTimeout = 50ms;
// Decoder faults are summarised in one event per this much station time [s].
constexpr double kFaultReportPeriodS = 1.0;
// The buffer holds this much stream when nobody polls, then drops the oldest [s].
constexpr double kBufferSpanS = 120.0;

Parity parse_parity(const json& c, const std::string& where) {
  const std::string p = c.value("parity", "none");
  if (p == "none") return Parity::kNone;
  if (p == "even") return Parity::kEven;
  if (p == "odd") return Parity::kOdd;
  throw core::InputError(where + ".parity", fmt::format("\"{}\" is not none, even or odd", p));
}

template <typename T>
T field(const json& c, const char* key, T fallback, const std::string& where) {
  if (!c.contains(key)) return fallback;
  try {
    return c.at(key).get<T>();
  } catch (const json::exception&) {
    throw core::InputError(where + "." + key, fmt::format("has the wrong type ({})", c.at(key).dump()));
  }
}

}  // namespace

SerialImuConnection SerialImuConnection::from_json(const json& c, const std::string& where) {
  if (!c.is_object()) throw core::InputError(where, "must be an object");
  SerialImuConnection out;
  out.serial.path = field<std::string>(c, "path", "", where);
  out.serial.baud_rate = field<int>(c, "baud", 115200, where);
  out.serial.parity = parse_parity(c, where);
  out.format = field<std::string>(c, "format", "calstand", where);
  out.sample_rate_hz = field<double>(c, "sample_rate_hz", 0.0, where);
  out.sequence_modulus = field<std::uint64_t>(c, "sequence_modulus", out.sequence_modulus, where);
  if (out.serial.path.empty()) {
    throw core::InputError(where + ".path", "is required: the serial device, e.g. /dev/ttyUSB0");
  }
  try {
    out.serial.validate();
  } catch (const core::InputError& e) {
    // validate() names "serial.<field>"; say which IMU's connection it is.
    throw core::InputError(where, e.what());
  }
  if (!(out.sample_rate_hz > 0.0 && out.sample_rate_hz <= 100000.0)) {
    throw core::InputError(where + ".sample_rate_hz",
                           "is required: the IMU's output rate in Hz (0 < rate <= 100000)");
  }
  if (out.sequence_modulus < 2 || out.sequence_modulus > (std::uint64_t{1} << 32)) {
    throw core::InputError(where + ".sequence_modulus", "must be in [2, 2^32]");
  }
  make_frame_decoder(out.format, out.sequence_modulus, where + ".format");  // checks the name
  return out;
}

std::unique_ptr<FrameDecoder> make_frame_decoder(const std::string& format,
                                                 std::uint64_t sequence_modulus,
                                                 const std::string& where) {
  if (format == "calstand") return std::make_unique<CalstandFrameDecoder>(sequence_modulus);
  throw core::InputError(where, fmt::format("unknown frame format \"{}\" (known: calstand)", format));
}

SerialImu::SerialImu(const core::ImuConfig& config, core::Clock& clock, const std::string& where)
    : name_(config.name), clock_(clock) {
  const auto c = SerialImuConnection::from_json(config.connection, where);
  auto port = std::make_unique<SerialPort>(c.serial);
  port_ = port.get();
  transport_ = std::move(port);
  decoder_ = make_frame_decoder(c.format, c.sequence_modulus, where + ".format");
  sample_rate_hz_ = c.sample_rate_hz;
  sequence_modulus_ = c.sequence_modulus;
}

SerialImu::SerialImu(std::string name, std::unique_ptr<ByteTransport> transport,
                     std::unique_ptr<FrameDecoder> decoder, double sample_rate_hz,
                     std::uint64_t sequence_modulus, core::Clock& clock)
    : name_(std::move(name)),
      clock_(clock),
      transport_(std::move(transport)),
      decoder_(std::move(decoder)),
      sample_rate_hz_(sample_rate_hz),
      sequence_modulus_(sequence_modulus) {}

SerialImu::~SerialImu() { stop_reader(); }

Result SerialImu::configure() {
  stop_reader();
  if (port_) {
    try {
      port_->open();
    } catch (const std::exception& e) {
      life_.set(DeviceState::kError);
      return Result::failure(e.what());
    }
  }
  life_.set(DeviceState::kInactive);
  return Result::success();
}

Result SerialImu::activate() {
  if (auto r = life_.activate(); !r) return r;
  if (!running_) {
    {
      std::lock_guard lock(mutex_);
      buffer_.clear();  // what arrived before activation belongs to nobody
    }
    sample_clock_.reset();
    last_report_s_ = clock_.now_s();
    running_ = true;
    reader_ = std::thread([this] { read_loop(); });
  }
  return Result::success();
}

Result SerialImu::deactivate() {
  stop_reader();
  life_.deactivate();
  return Result::success();
}

void SerialImu::stop_reader() {
  running_ = false;
  if (reader_.joinable()) reader_.join();
}

std::vector<core::ImuSample> SerialImu::poll() {
  std::vector<core::ImuSample> out;
  std::lock_guard lock(mutex_);
  out.swap(buffer_);
  return out;
}

std::map<std::string, std::uint64_t> SerialImu::fault_counters() const {
  auto out = faults_.snapshot();
  std::lock_guard lock(mutex_);
  for (const auto& [k, v] : decoder_counters_) out[k] = v;
  return out;
}

void SerialImu::read_loop() {
  std::array<std::uint8_t, 4096> chunk{};
  std::vector<core::ImuSample> decoded;
  const auto capacity = static_cast<std::size_t>(
      std::max(10000.0, kBufferSpanS * sample_rate_hz_));
  while (running_) {
    const IoResult r = transport_->read(chunk, kReadTimeout);
    const double arrival_s = clock_.now_s();
    if (!r.ok()) {
      faults_.add("read_errors");
      events_.push(arrival_s, true, "link lost: " + r.error);
      life_.set(DeviceState::kError);
      if (!reopen()) return;  // deactivated while waiting
      events_.push(clock_.now_s(), false, "link back");
      life_.set(DeviceState::kActive);
      continue;
    }
    decoded.clear();
    decoder_->feed(std::span(chunk.data(), r.bytes), decoded);
    for (auto& s : decoded) s.receive_time_s = sample_clock_.stamp(s.device_time_s, arrival_s);
    {
      std::lock_guard lock(mutex_);
      buffer_.insert(buffer_.end(), decoded.begin(), decoded.end());
      if (buffer_.size() > capacity) {
        // Nobody is draining: keep the newest, say how many went.
        const auto excess = buffer_.size() - capacity;
        buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(excess));
        faults_.add("buffer_overflows", excess);
      }
      decoder_counters_ = decoder_->counters();
    }
    report_decoder_faults(arrival_s, false);
  }
  report_decoder_faults(clock_.now_s(), true);
}

void SerialImu::report_decoder_faults(double now_s, bool force) {
  if (!force && now_s - last_report_s_ < kFaultReportPeriodS) return;
  const auto now = decoder_->counters();
  auto delta = [&](const char* key) {
    const auto it = now.find(key);
    const std::uint64_t v = it == now.end() ? 0 : it->second;
    return v - reported_counters_[key];
  };
  const auto crc = delta("crc_errors");
  const auto length = delta("length_errors");
  const auto garbage = delta("garbage_bytes");
  const auto resyncs = delta("resyncs");
  if (crc + length + garbage > 0) {
    events_.push(now_s, true,
                 fmt::format("frame errors in the last {:.1f} s: {} CRC, {} length, {} garbage "
                             "bytes in {} resyncs",
                             now_s - last_report_s_, crc, length, garbage, resyncs));
  }
  for (const char* key : {"crc_errors", "length_errors", "garbage_bytes", "resyncs"}) {
    const auto it = now.find(key);
    reported_counters_[key] = it == now.end() ? 0 : it->second;
  }
  last_report_s_ = now_s;
}

bool SerialImu::reopen() {
  // A replugged USB adapter comes back under the same path: retry with backoff while active.
  auto backoff = 100ms;
  while (running_) {
    if (port_) {
      try {
        port_->open();
        faults_.add("reopens");
        return true;
      } catch (const std::exception&) {
        // still gone; wait and retry
      }
    }
    for (auto waited = 0ms; waited < backoff && running_; waited += 10ms) {
      std::this_thread::sleep_for(10ms);
    }
    backoff = std::min(backoff * 2, std::chrono::milliseconds(5000));
  }
  return false;
}

std::unique_ptr<Imu> make_serial_imu(const core::ImuConfig& config, core::Clock& clock,
                                     const std::string& where) {
  return std::make_unique<SerialImu>(config, clock, where);
}

}  // namespace calstand::drivers

#include "drivers/serial_imu.hpp"

#include <fmt/format.h>

#include <chrono>
#include <span>

#include "core/error.hpp"
#include "core/schemas.hpp"
#include "drivers/imu_wire_format.hpp"

namespace calstand::drivers {
using nlohmann::json;

SerialImuConnection SerialImuConnection::from_json(const json& c, const std::string& where) {
  // The schema checks every field (path and rate required, a supported baud rate, the wire
  // format and its own options); what is left is reading them, with the defaults.
  core::validate_part_or_throw(
      core::schema_definition("station.schema.json", "serial_imu_connection"), c, "", where);
  SerialImuConnection out;
  out.serial.path = c.at("path").get<std::string>();
  out.serial.baud_rate = c.value("baud", 115200);
  out.serial.parity = parity_from_name(c.value("parity", "none"), where + ".parity");
  out.format = c.value("format", "calstand");
  out.settings.sample_rate_hz = c.at("sample_rate_hz").get<double>();
  out.settings.options = c.value(out.format, json::object());
  out.settings.where = where + "." + out.format;
  out.sequence_modulus = c.value("sequence_modulus", out.sequence_modulus);
  // The calstand frame's one option sits at the connection's top level (station files before
  // the wire formats); the format reads it from its options like any other.
  if (out.format == "calstand") out.settings.options = {{"sequence_modulus", out.sequence_modulus}};
  if (out.format != "calstand" && c.contains("sequence_modulus")) {
    throw core::InputError(where + ".sequence_modulus",
                           fmt::format("only for format calstand: a {} device's counter is the "
                                       "format's own (docs/protocols.md)",
                                       out.format));
  }
  return out;
}

SerialImu::SerialImu(const core::ImuConfig& config, core::Clock& clock, const std::string& where)
    : StreamingImu(config.name, clock) {
  auto c = SerialImuConnection::from_json(config.connection, where);
  // A station rehearsed K times faster than the wall (sim-station) has units that are too.
  c.settings.time_scale = clock.time_scale();
  const ImuWireFormat& format = imu_wire_format(c.format, where + ".format");
  auto port = std::make_unique<SerialPort>(c.serial);
  port_ = port.get();
  transport_ = std::move(port);
  sample_rate_hz_ = c.settings.sample_rate_hz;
  decoder_ = format.make_decoder(c.settings);
  sequence_modulus_ = format.sequence_modulus(c.settings);
  configurator_ = format.make_configurator(c.settings);
}

SerialImu::SerialImu(std::string name, std::unique_ptr<ByteTransport> transport,
                     std::unique_ptr<FrameDecoder> decoder, double sample_rate_hz,
                     std::uint64_t sequence_modulus, core::Clock& clock,
                     std::unique_ptr<ImuConfigurator> configurator)
    : StreamingImu(std::move(name), clock),
      transport_(std::move(transport)),
      decoder_(std::move(decoder)),
      configurator_(std::move(configurator)),
      sample_rate_hz_(sample_rate_hz),
      sequence_modulus_(sequence_modulus) {}

SerialImu::~SerialImu() { stop_reader(); }

std::optional<UnitIdentity> SerialImu::identity() const {
  std::lock_guard lock(identity_mutex_);
  return identity_;
}

void SerialImu::configure_device() {
  if (!configurator_) return;
  UnitIdentity id = configurator_->configure(*transport_);
  decoder_->identified(id);
  std::lock_guard lock(identity_mutex_);
  identity_ = std::move(id);
}

void SerialImu::on_reader_start() {
  // Bytes the line received while the device was inactive belong to nobody, like the buffer;
  // the flush may cut a frame, whose tail the decoder then drops uncounted.
  if (port_) port_->discard_input();
  decoder_->restart();
}

void SerialImu::open_link(bool /*after_error*/) {
  // SerialPort::open() reopens an open port, so a dead one needs no closing first.
  if (port_) port_->open();
  configure_device();
}

bool SerialImu::reopen_link() {
  if (!port_) return false;  // an injected link cannot be reopened: wait for deactivate()
  port_->open();
  // A device that lost power with its link forgot its configuration: say it again.
  configure_device();
  decoder_->restart();
  return true;
}

Result SerialImu::read_step() {
  const IoResult r = transport_->read(chunk_, kReadTimeout);
  const double arrival_s = clock().now_s();
  if (!r.ok()) return Result::failure(r.error);
  decoded_.clear();
  decoder_->feed(std::span(chunk_.data(), r.bytes), decoded_);
  stamp(decoded_, arrival_s);
  deliver(decoded_);
  publish_protocol_counters(decoder_->counters());
  // A status word flagging a fault comes with every frame (2000 a second): gathered here and
  // said once per summary, with how often.
  for (std::string& report : decoder_->take_device_reports()) ++device_reports_[std::move(report)];
  return Result::success();
}

void SerialImu::summarise_faults(double now_s, double period_s) {
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
    events().push(now_s, true,
                  fmt::format("frame errors in the last {:.1f} s: {} CRC, {} length, {} garbage "
                              "bytes in {} resyncs",
                              period_s, crc, length, garbage, resyncs));
  }
  for (const auto& [report, count] : device_reports_) {
    events().push(now_s, true,
                  count == 1 ? "the device reports: " + report
                             : fmt::format("the device reports: {} ({} times in the last {:.1f} s)",
                                           report, count, period_s));
  }
  device_reports_.clear();
  for (const char* key : {"crc_errors", "length_errors", "garbage_bytes", "resyncs"}) {
    const auto it = now.find(key);
    reported_counters_[key] = it == now.end() ? 0 : it->second;
  }
}

std::unique_ptr<Imu> make_serial_imu(const core::ImuConfig& config, core::Clock& clock,
                                     const std::string& where) {
  return std::make_unique<SerialImu>(config, clock, where);
}

}  // namespace calstand::drivers

#include "drivers/protocol_simulator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"
#include "drivers/acutrol_protocol.hpp"
#include "drivers/acutrol_server.hpp"
#if CALSTAND_WITH_SOCKETCAN
#include "drivers/can_sample_streamer.hpp"
#include "drivers/can_signal_map.hpp"
#include "drivers/socketcan_port.hpp"
#endif
#include "drivers/chamber_register_map.hpp"
#include "drivers/command_set_backends.hpp"
#include "drivers/command_set_server.hpp"
#include "drivers/imu_frame_streamer.hpp"
#include "drivers/imu_wire_format.hpp"
#include "drivers/modbus_chamber_server.hpp"
#include "drivers/scpi_server.hpp"
#include "drivers/sim_world_runner.hpp"

namespace calstand::drivers {

using nlohmann::json;

namespace {
/// The address clients connect to: the listening one, or loopback when it listens on all.
std::string connect_host(const std::string& listen_host) {
  return listen_host == "0.0.0.0" ? "127.0.0.1" : listen_host;
}

/// How the simulated chamber is served in one protocol. Today every chamber protocol is a
/// register map over Modbus TCP; a protocol served otherwise (a line command set) gets its own
/// entry kind here and its own server in start().
struct ChamberProtocol {
  const char* name;
  ChamberRegisterMap (*modbus_map)();
};

ChamberRegisterMap f4t_map() { return watlow_f4t_map(); }

constexpr ChamberProtocol kChamberProtocols[] = {
    {"watlow-f4t", &f4t_map},
    {"watlow-f4", &watlow_f4_map},
    {"csz-ezt570", &csz_ezt570_map},
};

/// The table's own protocol simulator (AcutrolServer); every other table protocol is a command
/// set served by a CommandSetHandler.
constexpr const char* kAcutrolProtocol = "acutrol";

const ChamberProtocol* find_chamber_protocol(const std::string& name) {
  for (const auto& p : kChamberProtocols) {
    if (name == p.name) return &p;
  }
  return nullptr;
}

ProtocolSimOptions validated(ProtocolSimOptions options) {
  options.validate();
  return options;
}

}  // namespace

std::string chamber_protocol_names() {
  std::string out;
  for (const auto& p : kChamberProtocols) out += (out.empty() ? "" : ", ") + std::string(p.name);
  for (const auto& n : line::builtin_command_set_names(line::DeviceKind::kChamber)) out += ", " + n;
  return out + ", or a chamber command-set file";
}

std::string table_protocol_names() {
  std::string out = kAcutrolProtocol;
  for (const auto& n : line::builtin_command_set_names(line::DeviceKind::kTable)) out += ", " + n;
  return out + ", or a table command-set file";
}

namespace {

/// The command set `protocol` names for `device` (a built-in or a file), or nullopt when it is
/// served otherwise (Modbus maps, the acutrol server). Throws core::InputError naming `option`.
std::optional<line::CommandSet> command_set_protocol(const std::string& protocol,
                                                     line::DeviceKind device,
                                                     const std::string& option,
                                                     const std::string& known) {
  const bool is_file = protocol.find('/') != std::string::npos || protocol.ends_with(".json");
  if (!is_file && !line::builtin_command_set(protocol)) {
    throw core::InputError(
        option, fmt::format("\"{}\" is not a protocol sim-station serves ({})", protocol, known));
  }
  return line::load_command_set(protocol, "", device, option);
}

std::optional<line::CommandSet> chamber_command_set(const ProtocolSimOptions& o) {
  if (find_chamber_protocol(o.chamber_protocol) != nullptr) return std::nullopt;
  return command_set_protocol(o.chamber_protocol, line::DeviceKind::kChamber, "--chamber-protocol",
                              chamber_protocol_names());
}

std::optional<line::CommandSet> table_command_set(const ProtocolSimOptions& o) {
  if (o.table_protocol == kAcutrolProtocol) return std::nullopt;
  return command_set_protocol(o.table_protocol, line::DeviceKind::kTable, "--table-protocol",
                              table_protocol_names());
}

}  // namespace

void ProtocolSimOptions::validate() const {
  chamber_command_set(*this);
  table_command_set(*this);
}

struct ProtocolSimulator::Impl {
  Impl(const core::StationConfig& config, ProtocolSimOptions o)
      : options(std::move(o)),
        sim_config(config),
        runner(config, options.time_scale),
        table_backend(runner.world(), runner.mutex()),
        chamber_backend(runner.world(), runner.mutex()),
        table_set(table_command_set(options)),
        chamber_set(chamber_command_set(options)) {}

  ProtocolSimOptions options;
  core::StationConfig sim_config;
  SimWorldRunner runner;
  SimTableBackend table_backend;
  SimChamberBackend chamber_backend;
  std::optional<line::CommandSet> table_set;    ///< the table's command set, if served in one
  std::optional<line::CommandSet> chamber_set;  ///< the chamber's command set, if served in one
  std::unique_ptr<AcutrolServer> table_server;
  std::unique_ptr<AcutrolServer> chamber_line_server;  ///< the chamber in its command set
  std::unique_ptr<ModbusChamberServer> chamber_tcp_server;
  std::unique_ptr<ModbusChamberServer> f4_server;
  std::vector<std::unique_ptr<ImuFrameStreamer>> imu_lines;
  /// One SCPI server per simulated supply, in the station file's order.
  std::vector<std::unique_ptr<ScpiServer>> supply_servers;
#if CALSTAND_WITH_SOCKETCAN
  std::unique_ptr<CanSampleStreamer> can;  // the first IMU on CAN, when asked
#else
  struct NoCan {
    void push(const core::ImuSample&) {}
    void set_silent(bool) {}
    std::uint64_t frames_sent() const { return 0; }
    std::uint64_t frames_dropped() const { return 0; }
  };
  std::unique_ptr<NoCan> can;
#endif
  bool started = false;

  /// IMU `i`'s wire format: by its name, else "*", else the calstand frame.
  std::string imu_format(std::size_t i) const {
    for (const std::string& key : {sim_config.imus.at(i).name, std::string("*")}) {
      if (const auto it = options.imu_formats.find(key); it != options.imu_formats.end()) {
        return it->second;
      }
    }
    return "calstand";
  }
  /// Who IMU `i` says it is on its line: its station entry's serial (or one made of its
  /// index: a device always has one) and the simulator as model and firmware.
  EmulatedUnit unit(std::size_t i) {
    const core::ImuConfig& imu = sim_config.imus.at(i);
    EmulatedUnit u;
    u.model = imu.model.empty() ? "calstand-sim" : imu.model;
    // Digits: several protocols carry the serial as a number (Xsens' device id, VectorNav's
    // serial register), the others as up to 8 ASCII characters.
    u.serial = imu.serial.empty() ? std::to_string(29000001 + i) : imu.serial;
    u.firmware = "calstand-sim 1.0";
    u.native_rate_hz = runner.world().imu(i).truth().sample_rate_hz;
    return u;
  }
};

ProtocolSimulator::ProtocolSimulator(const core::StationConfig& sim_config,
                                     ProtocolSimOptions options)
    : impl_(std::make_unique<Impl>(sim_config, validated(std::move(options)))) {}

ProtocolSimulator::~ProtocolSimulator() { stop(); }

SimWorldRunner& ProtocolSimulator::runner() { return impl_->runner; }

void ProtocolSimulator::start() {
  auto& m = *impl_;
  if (m.started) return;
  AcutrolServerOptions table_options;
  table_options.bind_host = m.options.host;
  table_options.port = static_cast<std::uint16_t>(m.options.table_port);
  m.table_backend.set_clock([&runner = m.runner] { return runner.clock_s(); });
  if (m.table_set) {
    m.table_server = line::make_command_set_server(
        std::make_shared<line::CommandSetHandler>(*m.table_set, m.table_backend), table_options);
  } else {
    m.table_server = std::make_unique<AcutrolServer>(m.table_backend, table_options);
  }
  m.table_server->start();
  if (m.chamber_set) {
    AcutrolServerOptions chamber_options;
    chamber_options.bind_host = m.options.host;
    m.chamber_line_server = line::make_command_set_server(
        std::make_shared<line::CommandSetHandler>(*m.chamber_set, m.chamber_backend),
        chamber_options);
    m.chamber_line_server->start();
  } else {
    const ChamberProtocol& chamber = *find_chamber_protocol(m.options.chamber_protocol);
    m.chamber_tcp_server = ModbusChamberServer::tcp(chamber.modbus_map(), m.chamber_backend,
                                                    m.options.modbus_port, 1, m.options.host);
    m.chamber_tcp_server->start();
  }
  if (m.options.f4_rtu) {
    m.f4_server = ModbusChamberServer::rtu(watlow_f4_map(), m.chamber_backend);
    m.f4_server->start();
  }
  for (std::size_t i = 0; i < m.runner.world().imu_count(); ++i) {
    const ImuWireFormat& format = imu_wire_format(m.imu_format(i), "--imu-format");
    m.imu_lines.push_back(std::make_unique<ImuFrameStreamer>(format.make_emulator(m.unit(i))));
  }
  // Each supply as a bench supply speaking SCPI on TCP, switching its IMU in the world.
  for (const core::PowerSupplyConfig& supply : m.sim_config.power_supplies) {
    std::size_t imu_index = 0;
    while (imu_index < m.sim_config.imus.size() &&
           m.sim_config.imus[imu_index].name != supply.imu) {
      ++imu_index;
    }
    AcutrolServerOptions supply_options;
    supply_options.bind_host = m.options.host;
    m.supply_servers.push_back(
        std::make_unique<ScpiServer>(m.runner.world(), m.runner.mutex(), imu_index,
                                     supply.voltage_v, supply.current_limit_a, supply_options));
    m.supply_servers.back()->start();
  }
  if (!m.options.can_interface.empty()) {
    if (m.options.can_map_file.empty()) {
      throw core::InputError("--can-map", "a CAN signal map is needed to send IMU frames on CAN");
    }
#if CALSTAND_WITH_SOCKETCAN
    auto port = std::make_unique<SocketCanPort>(m.options.can_interface);
    port->open();
    m.can = std::make_unique<CanSampleStreamer>(
        std::move(port), CanSignalMap::load(m.options.can_map_file, "--can-map"));
#else
    throw core::InputError("--can", "this calstand was built without SocketCAN");
#endif
  }
  {
    // Every sample the world produces goes out on the lines, from the world's thread.
    std::lock_guard lock(m.runner.mutex());
    m.runner.world().set_sample_sink([this](std::size_t i, const core::ImuSample& s) {
      impl_->imu_lines[i]->push(s);
      if (impl_->can && i == 0) impl_->can->push(s);
    });
  }
  m.runner.start();
  m.started = true;
}

void ProtocolSimulator::stop() {
  auto& m = *impl_;
  if (!m.started) return;
  m.runner.stop();
  if (m.table_server) m.table_server->stop();
  if (m.chamber_line_server) m.chamber_line_server->stop();
  if (m.chamber_tcp_server) m.chamber_tcp_server->stop();
  if (m.f4_server) m.f4_server->stop();
  for (auto& server : m.supply_servers) server->stop();
  m.supply_servers.clear();
  m.imu_lines.clear();
  m.can.reset();
  m.started = false;
}

json ProtocolSimulator::endpoints() const {
  auto& m = *impl_;  // the world's names and truths never change: no lock needed
  json imus = json::array();
  for (std::size_t i = 0; i < m.imu_lines.size(); ++i) {
    json entry = {{"name", m.runner.world().imu_name(i)},
                  {"serial", m.imu_lines[i]->path()},
                  {"format", m.imu_format(i)}};
    if (m.can && i == 0) entry["can"] = m.options.can_interface;
    imus.push_back(std::move(entry));
  }
  json chamber;
  if (m.chamber_line_server) {
    chamber = {
        {"tcp", fmt::format("{}:{}", connect_host(m.options.host), m.chamber_line_server->port())},
        {"protocol", m.options.chamber_protocol}};
  } else {
    chamber = {{"modbus_tcp",
                fmt::format("{}:{}", connect_host(m.options.host), m.chamber_tcp_server->port())},
               {"map", m.options.chamber_protocol}};
  }
  if (m.f4_server)
    chamber["modbus_rtu"] = {{"path", m.f4_server->slave_path()}, {"map", "watlow-f4"}};
  json supplies = json::array();
  for (std::size_t i = 0; i < m.supply_servers.size(); ++i) {
    supplies.push_back(
        {{"name", m.sim_config.power_supplies[i].name},
         {"imu", m.sim_config.power_supplies[i].imu},
         {"tcp", fmt::format("{}:{}", connect_host(m.options.host), m.supply_servers[i]->port())},
         {"protocol", "scpi"}});
  }
  return {{"sim_station", m.sim_config.name},
          {"time_scale", m.options.time_scale},
          {"power_supplies", supplies},
          {"table",
           {{"tcp", fmt::format("{}:{}", connect_host(m.options.host), m.table_server->port())},
            {"protocol", m.options.table_protocol}}},
          {"chamber", chamber},
          {"imus", imus}};
}

core::StationConfig ProtocolSimulator::client_station() const {
  auto& m = *impl_;  // the world's names and truths never change: no lock needed
  core::StationConfig c = m.sim_config;
  c.name = m.sim_config.name + " (via sim-station)";
  c.time_scale = m.options.time_scale;
  // Link-health thresholds guard against operating-system and link delays, which do not speed
  // up with the world: scaled by K they keep their wall-clock meaning (a 1 s stale-stream rule
  // at K = 20 would otherwise fire on a 50 ms scheduling hiccup).
  c.policy.stale_after_s = m.sim_config.policy.stale_after_s * m.options.time_scale;
  c.table.backend = "acutrol";
  c.table.connection = {{"transport", "tcp"},
                        {"host", connect_host(m.options.host)},
                        {"port", m.table_server->port()}};
  if (m.table_set) {
    const auto naming = line::station_naming(m.options.table_protocol, line::DeviceKind::kTable);
    c.table.backend = naming.backend;
    c.table.command_set = naming.command_set;
  }
  if (m.chamber_set) {
    const auto naming =
        line::station_naming(m.options.chamber_protocol, line::DeviceKind::kChamber);
    c.chamber.backend = naming.backend;
    c.chamber.command_set = naming.command_set;
    c.chamber.connection = {{"transport", "tcp"},
                            {"host", connect_host(m.options.host)},
                            {"port", m.chamber_line_server->port()}};
  } else {
    c.chamber.backend = "modbus";
    c.chamber.connection = {
        {"transport", "tcp"},
        {"host", connect_host(m.options.host)},
        {"port", m.chamber_tcp_server->port()},
        {"unit_id", 1},
        {"map", m.options.chamber_protocol},
        // Poll as often in world time as a lab station does (4 Hz); the
        // staleness rule (5 s in a lab) scaled as the policy above.
        {"poll_period_ms",
         std::max(10, static_cast<int>(std::lround(250.0 / m.options.time_scale)))},
        {"stale_after_s", 5.0 * m.options.time_scale}};
  }
  for (std::size_t i = 0; i < c.imus.size(); ++i) {
    auto& imu = c.imus[i];
    const auto& truth = m.runner.world().imu(i).truth();
    imu.backend = "serial";
    imu.model.clear();
    imu.spec_file.clear();
    imu.truth_file.clear();
    imu.truth = nullptr;
    const std::string format = m.imu_format(i);
    imu.connection = {{"path", m.imu_lines.at(i)->path()},
                      {"baud", 921600},
                      {"format", format},
                      {"sample_rate_hz", truth.sample_rate_hz}};
    if (format == "calstand") imu.connection["sequence_modulus"] = truth.sequence_modulus;
    // The unit says who it is over the wire now; the station entry's serial stays what a lab
    // would write (the unit expected in this slot).
  }
  for (std::size_t i = 0; i < c.power_supplies.size() && i < m.supply_servers.size(); ++i) {
    auto& supply = c.power_supplies[i];
    supply.backend = "scpi";
    supply.connection = {{"transport", "tcp"},
                         {"host", connect_host(m.options.host)},
                         {"port", m.supply_servers[i]->port()},
                         {"model", "generic"}};
  }
  return c;
}

void ProtocolSimulator::open_interlock(TableAxis axis, const std::string& why) {
  impl_->table_backend.open_interlock(
      axis == TableAxis::kOuter ? acutrol::kOuterAxis : acutrol::kInnerAxis, why);
}

void ProtocolSimulator::clear_interlock_cause(TableAxis axis) {
  impl_->table_backend.clear_interlock_cause(axis == TableAxis::kOuter ? acutrol::kOuterAxis
                                                                       : acutrol::kInnerAxis);
}

void ProtocolSimulator::set_modbus_running(bool running) {
  for (auto* server : {impl_->chamber_tcp_server.get(), impl_->f4_server.get()}) {
    if (!server) continue;
    if (running) {
      server->start();
    } else {
      server->stop();
    }
  }
}

void ProtocolSimulator::set_table_link(bool up) {
  auto& server = *impl_->table_server;
  // Refuse first, so that a client reconnecting between the two calls is refused too.
  server.set_refusing(!up);
  if (!up) server.drop_clients();
}

void ProtocolSimulator::set_imu_silent(std::size_t index, bool silent) {
  impl_->imu_lines.at(index)->set_silent(silent);
  if (impl_->can && index == 0) impl_->can->set_silent(silent);
}

void ProtocolSimulator::inject_imu_bytes(std::size_t index, std::vector<std::uint8_t> bytes) {
  impl_->imu_lines.at(index)->inject(std::move(bytes));
}

void ProtocolSimulator::set_imu_held(std::size_t index, bool held) {
  impl_->imu_lines.at(index)->set_held(held);
}

void ProtocolSimulator::jump_imu_clock(std::size_t index, double seconds) {
  impl_->imu_lines.at(index)->jump_clock(seconds);
}

std::size_t ProtocolSimulator::imu_index(const std::string& name) const {
  auto& world = impl_->runner.world();
  for (std::size_t i = 0; i < world.imu_count(); ++i) {
    if (world.imu_name(i) == name) return i;
  }
  throw core::InputError("imu", fmt::format("no IMU \"{}\" in the simulated station", name));
}

json ProtocolSimulator::statistics() const {
  auto& m = *impl_;  // the world's names and truths never change: no lock needed
  json imus = json::array();
  for (std::size_t i = 0; i < m.imu_lines.size(); ++i) {
    imus.push_back({{"name", m.runner.world().imu_name(i)},
                    {"frames_sent", m.imu_lines[i]->frames_sent()},
                    {"frames_dropped", m.imu_lines[i]->frames_dropped()}});
  }
  return {{"world_lag_s", m.runner.lag_s()},
          {"table_commands", m.table_server ? m.table_server->commands_served() : 0},
          {"modbus_requests", m.chamber_tcp_server ? m.chamber_tcp_server->requests() : 0},
          {"can_frames_sent", m.can ? m.can->frames_sent() : 0},
          {"can_frames_dropped", m.can ? m.can->frames_dropped() : 0},
          {"imus", imus}};
}

}  // namespace calstand::drivers

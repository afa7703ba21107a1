// `calstand sim-station`: one simulated world behind the real protocols (table command server,
// chamber over Modbus TCP in the map --chamber-protocol names and as an F4 over RTU, IMUs on
// pseudo-terminals in their wire format), so that the real drivers and the engine can be
// rehearsed end to end on this machine. Prints the endpoints as one line of JSON on start;
// `--station-out` writes the station file that points the real drivers at them.
//
// While it runs, lines on stdin rehearse faults (one JSON line answers each):
//   interlock open outer|inner [WHY...]   interlock clear outer|inner
//   modbus stop | modbus start            table drop | table restore (its TCP link)
//   imu silent NAME | imu talk NAME
//   imu garbage NAME N                    imu hold NAME | imu release NAME (a burst)
//   imu clock-jump NAME SECONDS           status | quit
#include <fmt/format.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "drivers/imu_wire_format.hpp"
#include "drivers/protocol_simulator.hpp"
#include "drivers/sim_world_runner.hpp"
#include "sim/sim_world.hpp"

namespace calstand::cli {
namespace {

using nlohmann::json;

struct SimStationOptions {
  std::string station_file;
  std::vector<std::string> imu_formats;  // "FORMAT" (every IMU) or "NAME=FORMAT"
  std::string station_out;
  drivers::ProtocolSimOptions serve;
  bool no_rtu = false;
  double duration_s = 0.0;  // 0: until a signal or `quit`
};

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

drivers::TableAxis parse_axis(const std::string& word) {
  if (word == "outer") return drivers::TableAxis::kOuter;
  if (word == "inner") return drivers::TableAxis::kInner;
  throw core::InputError("axis", fmt::format("\"{}\" is not outer or inner", word));
}

/// Executes one stdin command; returns the answer line. "quit" sets `quit`.
json execute_fault_command(drivers::ProtocolSimulator& sim, const std::string& line, bool& quit) {
  std::istringstream in(line);
  std::string verb, what, arg;
  in >> verb >> what >> arg;
  std::string rest;
  std::getline(in, rest);
  if (!rest.empty() && rest.front() == ' ') rest.erase(0, 1);
  if (verb == "quit") {
    quit = true;
    return {{"ok", true}};
  }
  if (verb == "status") return {{"ok", true}, {"statistics", sim.statistics()}};
  if (verb == "interlock" && what == "open") {
    std::string why = rest.empty() ? "interlock open (door)" : rest;
    sim.open_interlock(parse_axis(arg), why);
    return {{"ok", true}};
  }
  if (verb == "interlock" && what == "clear") {
    sim.clear_interlock_cause(parse_axis(arg));
    return {{"ok", true}};
  }
  if (verb == "modbus" && (what == "stop" || what == "start")) {
    sim.set_modbus_running(what == "start");
    return {{"ok", true}};
  }
  if (verb == "table" && (what == "drop" || what == "restore")) {
    sim.set_table_link(what == "restore");
    return {{"ok", true}};
  }
  if (verb == "imu" && (what == "silent" || what == "talk")) {
    sim.set_imu_silent(sim.imu_index(arg), what == "silent");
    return {{"ok", true}};
  }
  if (verb == "imu" && what == "garbage") {
    const auto index = sim.imu_index(arg);
    const long count = std::strtol(rest.c_str(), nullptr, 10);
    if (count <= 0 || count > 1'000'000) throw core::InputError("count", "must be 1..1000000");
    std::mt19937 rng(static_cast<unsigned>(count));
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(count));
    for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
    sim.inject_imu_bytes(index, std::move(bytes));
    return {{"ok", true}};
  }
  if (verb == "imu" && (what == "hold" || what == "release")) {
    sim.set_imu_held(sim.imu_index(arg), what == "hold");
    return {{"ok", true}};
  }
  if (verb == "imu" && what == "clock-jump") {
    const auto index = sim.imu_index(arg);
    char* end = nullptr;
    const double seconds = std::strtod(rest.c_str(), &end);
    if (rest.empty() || end == rest.c_str() || !std::isfinite(seconds)) {
      throw core::InputError("seconds", "must be a number of seconds");
    }
    sim.jump_imu_clock(index, seconds);
    return {{"ok", true}};
  }
  throw core::InputError("command", fmt::format("\"{}\" is not understood (interlock open|clear "
                                                "AXIS, modbus stop|start, table drop|restore, "
                                                "imu silent|talk|garbage|"
                                                "hold|release|clock-jump NAME, status, quit)",
                                                line));
}

void run_sim_station(SimStationOptions opt) {
  const auto config = sim::load_station_or_default(opt.station_file);
  if (!config.is_simulated()) {
    throw core::InputError(opt.station_file,
                           "sim-station serves a simulated station; every "
                           "backend must be \"sim\"");
  }
  opt.serve.f4_rtu = !opt.no_rtu;
  for (const std::string& given : opt.imu_formats) {
    const auto eq = given.find('=');
    const std::string name = eq == std::string::npos ? "*" : given.substr(0, eq);
    const std::string format = eq == std::string::npos ? given : given.substr(eq + 1);
    drivers::imu_wire_format(format, "--imu-format " + given);  // throws naming the known ones
    if (name != "*") {
      const bool known = std::any_of(config.imus.begin(), config.imus.end(),
                                     [&](const core::ImuConfig& imu) { return imu.name == name; });
      if (!known) {
        throw core::InputError("--imu-format " + given,
                               fmt::format("no IMU \"{}\" in the station", name));
      }
    }
    opt.serve.imu_formats[name] = format;
  }
  drivers::ProtocolSimulator sim(config, opt.serve);
  sim.start();
  if (!opt.station_out.empty()) {
    std::ofstream out(opt.station_out);
    out << sim.client_station().to_json().dump(2) << "\n";
    if (!out) throw std::runtime_error(opt.station_out + ": cannot write the station file");
  }
  json hello = sim.endpoints();
  if (!opt.station_out.empty()) hello["station_file"] = opt.station_out;
  std::cout << hello.dump() << std::endl;

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const auto start = std::chrono::steady_clock::now();
  bool stdin_open = true;
  bool quit = false;
  std::string pending;
  auto last_lag_warning = std::chrono::steady_clock::now() - std::chrono::hours(1);
  while (!g_stop && !quit) {
    // The world falling behind the clock the clients run on (time scale too high for this
    // machine) would make every timing of the rehearsal wrong: say so, at most every 10 s.
    if (const double lag = sim.runner().lag_s();
        lag > 1.0 * opt.serve.time_scale &&
        std::chrono::steady_clock::now() - last_lag_warning > std::chrono::seconds(10)) {
      std::cerr << fmt::format(
          "sim-station: warning: the world is {:.1f} s behind the wall "
          "clock x {}; lower --time-scale\n",
          lag, opt.serve.time_scale);
      last_lag_warning = std::chrono::steady_clock::now();
    }
    if (opt.duration_s > 0.0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
            opt.duration_s) {
      break;
    }
    if (!stdin_open) {
      ::usleep(100'000);
      continue;
    }
    pollfd pfd{STDIN_FILENO, POLLIN, 0};
    if (::poll(&pfd, 1, 100) <= 0) continue;
    char buf[4096];
    const ssize_t n = ::read(STDIN_FILENO, buf, sizeof buf);
    if (n <= 0) {
      stdin_open = false;  // serve on without commands (e.g. started with </dev/null)
      continue;
    }
    pending.append(buf, static_cast<std::size_t>(n));
    for (auto eol = pending.find('\n'); eol != std::string::npos; eol = pending.find('\n')) {
      const std::string line = pending.substr(0, eol);
      pending.erase(0, eol + 1);
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      json answer;
      try {
        answer = execute_fault_command(sim, line, quit);
      } catch (const std::exception& e) {
        answer = {{"ok", false}, {"error", e.what()}};
      }
      std::cout << answer.dump() << std::endl;
    }
  }
  sim.stop();
}

}  // namespace

void register_sim_station(CLI::App& app) {
  auto opt = std::make_shared<SimStationOptions>();
  auto* cmd =
      app.add_subcommand("sim-station",
                         "Serve a simulated station behind the real protocols (Modbus, table "
                         "commands, IMU frames) for rehearsing the real drivers");
  cmd->add_option("--station", opt->station_file, "station file (default: the built-in station)");
  cmd->add_option("--time-scale", opt->serve.time_scale, "world seconds per wall second")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 1000.0));
  cmd->add_option("--host", opt->serve.host, "listening address")->capture_default_str();
  cmd->add_option("--table-port", opt->serve.table_port, "table command port (0: any free)")
      ->capture_default_str();
  cmd->add_option("--modbus-port", opt->serve.modbus_port, "Modbus TCP port (0: any free)")
      ->capture_default_str();
  cmd->add_option("--chamber-protocol", opt->serve.chamber_protocol,
                  "the chamber's protocol on TCP: " + drivers::chamber_protocol_names())
      ->capture_default_str();
  cmd->add_option("--table-protocol", opt->serve.table_protocol,
                  "the table's command set on TCP: " + drivers::table_protocol_names())
      ->capture_default_str();
  cmd->add_flag("--no-rtu", opt->no_rtu, "do not serve the chamber as an F4 over RTU");
  cmd->add_option("--can", opt->serve.can_interface,
                  "also send the first IMU's samples on this CAN interface (e.g. vcan0)");
  cmd->add_option("--can-map", opt->serve.can_map_file, "CAN signal map for --can");
  cmd->add_option("--imu-format", opt->imu_formats,
                  "the IMUs' wire format: calstand (default), xsens, vectornav, epson, stim300; "
                  "FORMAT for every IMU or NAME=FORMAT for one (repeatable)");
  cmd->add_option("--station-out", opt->station_out,
                  "write the station file for the real drivers here");
  cmd->add_option("--duration", opt->duration_s, "stop after this many wall seconds (0: never)");
  cmd->callback([opt] { run_sim_station(*opt); });
}

}  // namespace calstand::cli

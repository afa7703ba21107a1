// `calstand device`: manual control of a real station's devices through the same drivers the
// engine uses, for setting up and debugging a station by hand:
//   calstand device --station lab.json status
//   calstand device --station lab.json chamber get|set TEMP [--ramp R] [--wait]|standby
//   calstand device --station lab.json table get|move --outer D --inner D|rate --axis A --dps
//   R|stop|close-interlock [--by NAME]
//   calstand device --station lab.json imu stream --count N [--imu NAME]
//   calstand device --station lab.json imu info [--imu NAME]
// Output is JSON (one object, or JSON lines for `imu stream`), so scripts can read it.
// A table or chamber whose link drops is ridden out as a run does (drivers/ride_out.hpp):
// reads, setpoints, demands and stops are repeated until the link is back, for up to the
// station's policy.link_outage_s; closing an interlock never is (an operator's act, once).
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/state_json.hpp"
#include "drivers/ride_out.hpp"
#include "drivers/station.hpp"
#include "sim/sim_world.hpp"
#include "store/stamp.hpp"

namespace calstand::cli {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;

struct DeviceOptions {
  std::string station_file;
  // chamber
  double temperature_c = 0.0;
  std::optional<double> ramp_c_per_min;
  bool wait = false;
  double tolerance_c = 0.5;
  // table
  double outer_deg = 0.0;
  double inner_deg = 0.0;
  std::string axis;
  double rate_dps = 0.0;
  double timeout_s = 600.0;
  // imu
  std::size_t count = 10;
  std::string imu_name;
  // close-interlock
  std::string by;
};

std::unique_ptr<drivers::Station> open_station(const DeviceOptions& opt) {
  const auto config = sim::load_station_or_default(opt.station_file);
  if (config.is_simulated()) {
    throw core::InputError(opt.station_file.empty() ? "--station" : opt.station_file,
                           "the station is simulated in process, so there is no device to talk "
                           "to; start `calstand sim-station --station-out lab.json` and use "
                           "that file");
  }
  return drivers::make_station(config);
}

void check(const drivers::Result& r, const std::string& what) {
  if (r) return;
  // Drivers usually name themselves already ("chamber: ramp ...", "table link down for ...");
  // do not say it twice.
  const bool named = r.message.rfind(what + ":", 0) == 0 || r.message.rfind(what + " ", 0) == 0;
  throw std::runtime_error(named ? r.message : what + ": " + r.message);
}

/// Rides out a dropped link for the station's policy.link_outage_s.
drivers::RideOutPolicy ride_out_policy(drivers::Station& station) {
  return drivers::RideOutPolicy::from_policy(station.config().policy);
}

/// `command` on `device`, repeated while its link is down (harmless commands only).
void ride_out(drivers::Station& station, drivers::Device& device,
              const std::function<drivers::Result()>& command) {
  check(drivers::ride_out(device.name(), station.clock(), ride_out_policy(station), command),
        device.name());
}

/// configure() and activate() one device; a failure ends the command (exit 1).
void bring_up(drivers::Station& station, drivers::Device& device) {
  ride_out(station, device, [&] { return device.configure(); });
  ride_out(station, device, [&] { return device.activate(); });
}

/// configure() only: reading needs the link, not activation (which would, e.g., try to close
/// an open interlock).
void configure(drivers::Station& station, drivers::Device& device) {
  ride_out(station, device, [&] { return device.configure(); });
}

core::TableState read_table(drivers::Station& station) {
  auto read = drivers::read_riding_out(station.table(), station.clock(), ride_out_policy(station));
  check(read.result, station.table().name());
  return read.state;
}

core::ChamberState read_chamber(drivers::Station& station) {
  auto read =
      drivers::read_riding_out(station.chamber(), station.clock(), ride_out_policy(station));
  check(read.result, station.chamber().name());
  return read.state;
}

json device_json(drivers::Device& d) {
  json events = json::array();
  for (const auto& e : d.take_events()) {
    events.push_back({{"time_s", e.time_s}, {"fault", e.fault}, {"message", e.message}});
  }
  json out = {{"name", d.name()},
              {"state", std::string(drivers::to_string(d.state()))},
              {"fault_counters", d.fault_counters()},
              {"events", events}};
  // An IMU whose protocol says who it is: as read over the wire.
  if (const auto* imu = dynamic_cast<const drivers::Imu*>(&d)) {
    if (const auto id = imu->identity()) {
      out["identity"] = {{"model", id->model}, {"serial", id->serial}, {"firmware", id->firmware}};
    }
  }
  return out;
}

void print(const json& j) { fmt::print("{}\n", j.dump()); }

/// A driver that polls in the background needs a moment for its first reading.
void settle_first_reading() { std::this_thread::sleep_for(300ms); }

void device_status(const DeviceOptions& opt) {
  auto station = open_station(opt);
  json devices = json::array();
  std::vector<drivers::Device*> all{&station->table(), &station->chamber()};
  for (std::size_t i = 0; i < station->imu_count(); ++i) all.push_back(&station->imu(i));
  for (auto* d : all) {
    const auto r = d->configure();
    json entry = device_json(*d);
    entry["configure"] = r ? "ok" : r.message;
    devices.push_back(std::move(entry));
  }
  print({{"station", station->config().name}, {"devices", devices}});
}

void chamber_get(const DeviceOptions& opt) {
  auto station = open_station(opt);
  configure(*station, station->chamber());
  settle_first_reading();
  json out = core::to_json(read_chamber(*station));
  out["device"] = device_json(station->chamber());
  print(out);
}

void chamber_set(const DeviceOptions& opt) {
  auto station = open_station(opt);
  auto& chamber = station->chamber();
  bring_up(*station, chamber);
  ride_out(*station, chamber,
           [&] { return chamber.set_temperature(opt.temperature_c, opt.ramp_c_per_min); });
  // The driver steps the setpoint itself when the controller cannot ramp: stay until the
  // setpoint has reached the target (and, with --wait, the air has too).
  auto& clock = station->clock();
  const double start = clock.now_s();
  for (;;) {
    std::this_thread::sleep_for(250ms);
    const auto s = read_chamber(*station);
    if (s.fault) throw std::runtime_error("chamber fault: " + s.fault_text);
    const bool setpoint_there = std::abs(s.setpoint_c - opt.temperature_c) < 0.05;
    const bool air_there = std::abs(s.air_temperature_c - opt.temperature_c) <= opt.tolerance_c;
    if (setpoint_there && (!opt.wait || air_there)) break;
    if (clock.now_s() - start > opt.timeout_s) {
      throw std::runtime_error(
          fmt::format("chamber did not reach {} degC within {:.0f} s "
                      "(air {:.2f}, setpoint {:.2f})",
                      opt.temperature_c, opt.timeout_s, s.air_temperature_c, s.setpoint_c));
    }
  }
  print(core::to_json(read_chamber(*station)));
}

void chamber_standby(const DeviceOptions& opt) {
  auto station = open_station(opt);
  auto& chamber = station->chamber();
  bring_up(*station, chamber);
  ride_out(*station, chamber, [&] { return chamber.standby(); });
  settle_first_reading();
  print(core::to_json(read_chamber(*station)));
}

void table_get(const DeviceOptions& opt) {
  auto station = open_station(opt);
  configure(*station, station->table());
  json out = core::to_json(read_table(*station));
  out["device"] = device_json(station->table());
  print(out);
}

/// Waits until `done(state)` or the timeout; a table fault ends the command.
template <typename Done>
void wait_table(drivers::Station& station, double timeout_s, Done done, const char* what) {
  const double start = station.clock().now_s();
  for (;;) {
    const auto s = read_table(station);  // rides a dropped link out; throws past the policy
    if (s.outer.fault || s.inner.fault) {
      station.table().stop();  // never leave an axis moving when the command gives up
      throw std::runtime_error("table fault: " +
                               (s.outer.fault ? s.outer.fault_text : s.inner.fault_text));
    }
    if (done(s)) return;
    if (station.clock().now_s() - start > timeout_s) {
      station.table().stop();
      throw std::runtime_error(
          fmt::format("table: {} not done within {:.0f} s (stopped)", what, timeout_s));
    }
    std::this_thread::sleep_for(20ms);
  }
}

void table_move(const DeviceOptions& opt) {
  auto station = open_station(opt);
  auto& table = station->table();
  bring_up(*station, table);
  ride_out(*station, table, [&] { return table.move_to(opt.outer_deg, opt.inner_deg); });
  std::this_thread::sleep_for(50ms);  // let the controller take the move before polling
  wait_table(
      *station, opt.timeout_s,
      [](const core::TableState& s) { return s.outer.in_position && s.inner.in_position; }, "move");
  print(core::to_json(read_table(*station)));
}

void table_rate(const DeviceOptions& opt) {
  const auto axis = opt.axis == "outer" ? drivers::TableAxis::kOuter : drivers::TableAxis::kInner;
  auto station = open_station(opt);
  auto& table = station->table();
  bring_up(*station, table);
  // The same rate demanded twice is the same rate: harmless to repeat.
  ride_out(*station, table, [&] { return table.set_rate(axis, opt.rate_dps); });
  std::this_thread::sleep_for(50ms);
  wait_table(
      *station, opt.timeout_s,
      [&](const core::TableState& s) {
        return (axis == drivers::TableAxis::kOuter ? s.outer : s.inner).in_position;
      },
      "rate");
  // The axis keeps turning after the command returns: that is what was asked for.
  print(core::to_json(read_table(*station)));
}

void table_stop(const DeviceOptions& opt) {
  auto station = open_station(opt);
  auto& table = station->table();
  table.configure();  // stop is allowed in every state; try even if the link is troubled
  ride_out(*station, table, [&] { return table.stop(); });
  print(core::to_json(read_table(*station)));
}

/// Who closes an interlock, for the record: --by, else the login name.
std::string operator_name(const DeviceOptions& opt) {
  if (!opt.by.empty()) return opt.by;
  for (const char* var : {"LOGNAME", "USER"}) {
    if (const char* v = std::getenv(var); v != nullptr && *v != '\0') return v;
  }
  return "operator";
}

void table_close_interlock(const DeviceOptions& opt) {
  auto station = open_station(opt);
  auto& table = station->table();
  configure(*station, table);  // the link only: activation refuses while an interlock is latched
  // Not repeated on a lost link: closing is the operator's act, done once, knowingly.
  const auto closure = table.close_interlocks();
  check(closure.result, "table");
  print({{"closed", closure.closed},
         {"by", operator_name(opt)},
         {"wall_utc", store::utc_now_iso8601()},
         {"table", core::to_json(table.read_state())}});
}

/// The IMU named --imu, else the first.
drivers::Imu& chosen_imu(drivers::Station& station, const DeviceOptions& opt) {
  if (opt.imu_name.empty()) return station.imu(0);
  for (std::size_t i = 0; i < station.imu_count(); ++i) {
    if (station.imu(i).name() == opt.imu_name) return station.imu(i);
  }
  throw core::InputError("--imu", fmt::format("no IMU \"{}\" in the station", opt.imu_name));
}

void imu_info(const DeviceOptions& opt) {
  auto station = open_station(opt);
  auto& imu = chosen_imu(*station, opt);
  configure(*station, imu);  // the configuration dialogue reads the identity; no streaming needed
  const std::optional<drivers::UnitIdentity> id = imu.identity();
  if (!id) {
    throw std::runtime_error(imu.name() +
                             ": its wire format carries no identity (the calstand frame, a CAN "
                             "map); the station file's \"serial\" names the unit instead");
  }
  print({{"imu", imu.name()},
         {"model", id->model},
         {"serial", id->serial},
         {"firmware", id->firmware},
         {"sample_rate_hz", imu.sample_rate_hz()}});
}

void imu_stream(const DeviceOptions& opt) {
  auto station = open_station(opt);
  auto& imu = chosen_imu(*station, opt);
  bring_up(*station, imu);
  const double period_s = 1.0 / imu.sample_rate_hz();
  const auto deadline =
      std::chrono::steady_clock::now() +
      std::chrono::duration<double>(10.0 + 2.0 * static_cast<double>(opt.count) * period_s);
  std::size_t printed = 0;
  while (printed < opt.count) {
    for (const auto& s : imu.poll()) {
      if (printed == opt.count) break;
      print({{"imu", imu.name()},
             {"sequence", s.sequence},
             {"device_time_s", s.device_time_s},
             {"receive_time_s", s.receive_time_s},
             {"gyro_dps", {s.gyro_dps.x(), s.gyro_dps.y(), s.gyro_dps.z()}},
             {"accel_mps2", {s.accel_mps2.x(), s.accel_mps2.y(), s.accel_mps2.z()}},
             {"temperature_c", s.temperature_c}});
      ++printed;
    }
    if (std::chrono::steady_clock::now() > deadline) {
      throw std::runtime_error(
          fmt::format("{}: {} of {} samples within the time allowed; "
                      "counters {}",
                      imu.name(), printed, opt.count, json(imu.fault_counters()).dump()));
    }
    std::this_thread::sleep_for(5ms);
  }
  imu.deactivate();
}

}  // namespace

void register_device(CLI::App& app) {
  auto opt = std::make_shared<DeviceOptions>();
  auto* cmd = app.add_subcommand("device", "Talk to a real station's devices by hand (JSON out)");
  cmd->add_option("--station", opt->station_file, "station file with real backends")->required();
  cmd->require_subcommand(1);

  cmd->add_subcommand("status", "configure every device; state, fault counters and events")
      ->callback([opt] { device_status(*opt); });

  auto* chamber = cmd->add_subcommand("chamber", "temperature chamber");
  chamber->require_subcommand(1);
  chamber->add_subcommand("get", "air temperature, setpoint, mode")->callback([opt] {
    chamber_get(*opt);
  });
  auto* set = chamber->add_subcommand("set", "control the air to TEMP degC");
  set->add_option("temperature", opt->temperature_c, "target [degC]")->required();
  set->add_option("--ramp", opt->ramp_c_per_min, "ramp [degC/min] (default: the chamber's)");
  set->add_flag("--wait", opt->wait, "wait until the air is within --tolerance of TEMP");
  set->add_option("--tolerance", opt->tolerance_c, "with --wait [degC]")->capture_default_str();
  set->add_option("--timeout", opt->timeout_s, "give up after this much station time [s]")
      ->capture_default_str();
  set->callback([opt] { chamber_set(*opt); });
  chamber->add_subcommand("standby", "stop controlling (safe state)")->callback([opt] {
    chamber_standby(*opt);
  });

  auto* table = cmd->add_subcommand("table", "rate table");
  table->require_subcommand(1);
  table->add_subcommand("get", "angles, rates, modes, faults")->callback([opt] {
    table_get(*opt);
  });
  auto* move = table->add_subcommand("move", "both axes to angles, wait until in position");
  move->add_option("--outer", opt->outer_deg, "outer axis angle [deg]")->required();
  move->add_option("--inner", opt->inner_deg, "inner axis angle [deg]")->required();
  move->add_option("--timeout", opt->timeout_s, "give up after this much station time [s]")
      ->capture_default_str();
  move->callback([opt] { table_move(*opt); });
  auto* rate = table->add_subcommand("rate", "turn one axis at a rate (it keeps turning)");
  rate->add_option("--axis", opt->axis, "outer or inner")
      ->required()
      ->check(CLI::IsMember({"outer", "inner"}));
  rate->add_option("--dps", opt->rate_dps, "rate [deg/s], signed")->required();
  rate->add_option("--timeout", opt->timeout_s, "give up after this much station time [s]")
      ->capture_default_str();
  rate->callback([opt] { table_rate(*opt); });
  table->add_subcommand("stop", "both axes to rest (safe state)")->callback([opt] {
    table_stop(*opt);
  });
  auto* close = table->add_subcommand(
      "close-interlock",
      "close latched axis interlocks (refused while their cause is present); nothing else "
      "closes them");
  close->add_option("--by", opt->by, "who closes them, for the record (default: login name)");
  close->callback([opt] { table_close_interlock(*opt); });

  auto* imu = cmd->add_subcommand("imu", "IMU streams");
  imu->require_subcommand(1);
  auto* stream = imu->add_subcommand("stream", "print samples as JSON lines");
  stream->add_option("--count", opt->count, "samples to print")->capture_default_str();
  stream->add_option("--imu", opt->imu_name, "IMU name (default: the first)");
  stream->callback([opt] { imu_stream(*opt); });
  auto* info =
      imu->add_subcommand("info", "the unit's model, serial and firmware as read over the wire");
  info->add_option("--imu", opt->imu_name, "IMU name (default: the first)");
  info->callback([opt] { imu_info(*opt); });
}

}  // namespace calstand::cli

// `calstand fleet`: the fleet's central database: create or migrate its schema, and ask it for
// the runs, units and calibration records of every station.
#include <fmt/format.h>

#include <string>

#include "central_option.hpp"
#include "commands.hpp"
#include "fleet/central_schema.hpp"
#include "fleet/fleet_queries.hpp"

namespace calstand::cli {
namespace {

struct FleetCliOptions {
  CentralOptions central;
  fleet::FleetFilter filter;
  bool as_json = false;
};

std::string text(const nlohmann::json& j) { return j.is_null() ? "-" : j.get<std::string>(); }

void run_migrate(const CentralOptions& central) {
  auto connection = open_central(central, "--to");
  const std::vector<int> applied = fleet::migrate_central(*connection);
  if (applied.empty()) {
    fmt::print("central schema already at version {}\n", fleet::central_schema_version());
  }
  for (int v : applied) {
    fmt::print("applied central migration {}: {}\n", v, fleet::central_migration_title(v));
  }
}

void run_stations(const FleetCliOptions& opt) {
  opt.filter.validate();
  auto connection = open_central(opt.central, "--from");
  const nlohmann::json stations = fleet::fleet_stations(*connection, opt.filter);
  if (opt.as_json) {
    fmt::print("{}\n", stations.dump(2));
    return;
  }
  fmt::print("{:<16} {:<36} {:>5} {:>6} {:>6} {:<24} {}\n", "station", "uuid", "runs", "units",
             "cals", "last run", "status");
  for (const auto& s : stations["stations"]) {
    fmt::print("{:<16} {:<36} {:>5} {:>6} {:>6} {:<24} {}\n", s["name"].get<std::string>(),
               s["uuid"].get<std::string>(), s["runs"].get<std::int64_t>(),
               s["units"].get<std::int64_t>(), s["calibrations"].get<std::int64_t>(),
               text(s["last_run_utc"]), text(s["last_run_status"]));
  }
}

void run_parameters(const FleetCliOptions& opt) {
  opt.filter.validate();
  auto connection = open_central(opt.central, "--from");
  const nlohmann::json parameters = fleet::fleet_parameters(*connection, opt.filter);
  if (opt.as_json) {
    fmt::print("{}\n", parameters.dump(2));
    return;
  }
  fmt::print("{:<28} {:<9} {:<16} {:>4} {:>12} {:>12} {:>12} {:>12}\n", "parameter", "unit",
             "station", "n", "mean", "std", "min", "max");
  for (const auto& p : parameters["parameters"]) {
    for (const auto& s : p["stations"]) {
      fmt::print(
          "{:<28} {:<9} {:<16} {:>4} {:>12.5g} {:>12} {:>12.5g} {:>12.5g}\n",
          p["name"].get<std::string>(), p["unit"].get<std::string>(),
          s["station"].get<std::string>(), s["n"].get<std::int64_t>(), s["mean"].get<double>(),
          s["std"].is_null() ? std::string("-") : fmt::format("{:.5g}", s["std"].get<double>()),
          s["min"].get<double>(), s["max"].get<double>());
    }
  }
}

void run_runs(const FleetCliOptions& opt) {
  opt.filter.validate();
  auto connection = open_central(opt.central, "--from");
  const nlohmann::json runs = fleet::fleet_runs(*connection, opt.filter);
  if (opt.as_json) {
    fmt::print("{}\n", runs.dump(2));
    return;
  }
  fmt::print("{:<16} {:>5} {:<22} {:<11} {:>9} {:<24} {}\n", "station", "run", "procedure",
             "status", "steps", "created", "units");
  for (const auto& r : runs["runs"]) {
    std::string units;
    for (const auto& u : r["units"]) {
      units += (units.empty() ? "" : ", ") + u["imu"].get<std::string>() + "=" +
               (u["serial"].get<std::string>().empty() ? "?" : u["serial"].get<std::string>());
    }
    fmt::print("{:<16} {:>5} {:<22} {:<11} {:>9} {:<24} {}\n", r["station"].get<std::string>(),
               r["run"].get<std::int64_t>(), r["procedure"].get<std::string>(),
               r["status"].get<std::string>(),
               fmt::format("{}/{}", r["steps_done"].get<std::int64_t>(),
                           r["steps_total"].get<std::int64_t>()),
               r["created_utc"].get<std::string>(), units.empty() ? "-" : units);
  }
}

void run_units(const FleetCliOptions& opt) {
  opt.filter.validate();
  auto connection = open_central(opt.central, "--from");
  const nlohmann::json units = fleet::fleet_units(*connection, opt.filter);
  if (opt.as_json) {
    fmt::print("{}\n", units.dump(2));
    return;
  }
  fmt::print("{:<16} {:<14} {:>5} {:>6} {:<14} {:<24} {}\n", "serial", "model", "runs", "cals",
             "verdict", "last run", "stations");
  for (const auto& u : units["units"]) {
    std::string stations;
    for (const auto& s : u["stations"]) {
      stations += (stations.empty() ? "" : ", ") + s.get<std::string>();
    }
    fmt::print("{:<16} {:<14} {:>5} {:>6} {:<14} {:<24} {}\n", u["serial"].get<std::string>(),
               u["model"].get<std::string>(), u["runs"].get<std::int64_t>(),
               u["calibrations"].get<std::int64_t>(), text(u["latest_verdict"]),
               u["last_run_utc"].get<std::string>(), stations);
  }
}

void run_calibrations(const FleetCliOptions& opt) {
  opt.filter.validate();
  auto connection = open_central(opt.central, "--from");
  const nlohmann::json records = fleet::fleet_calibrations(*connection, opt.filter);
  if (opt.as_json) {
    fmt::print("{}\n", records.dump(2));
    return;
  }
  fmt::print("{:>6} {:<16} {:>5} {:<6} {:<16} {:<24} {:<14} {}\n", "id", "station", "run", "imu",
             "serial", "created", "verdict", "in force");
  for (const auto& c : records["calibrations"]) {
    fmt::print("{:>6} {:<16} {:>5} {:<6} {:<16} {:<24} {:<14} {}\n", c["id"].get<std::int64_t>(),
               c.value("station", std::string("-")), c["run"].get<std::int64_t>(),
               c["imu"].get<std::string>(), c["serial"].get<std::string>(),
               c["created_utc"].get<std::string>(), text(c["verdict"]),
               c["in_force"].get<bool>() ? "yes" : "");
  }
}

}  // namespace

void register_fleet(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "fleet",
      "The fleet's central PostgreSQL database: migrate its schema; runs, units and "
      "calibration records of every station");
  cmd->require_subcommand(1);

  auto migrate = std::make_shared<CentralOptions>();
  auto* m = cmd->add_subcommand("migrate",
                                "Create or migrate the central schema, its roles and row-level "
                                "security (as the database's owner)");
  add_central_options(m, *migrate, "--to", "Central database", true);
  m->callback([migrate] { run_migrate(*migrate); });

  struct Query {
    const char* name;
    const char* help;
    void (*run)(const FleetCliOptions&);
  };
  for (const Query& q :
       {Query{"stations", "The stations registered, with their runs, units and last run",
              run_stations},
        Query{"runs", "Runs of every station, newest first", run_runs},
        Query{"units", "Units (by serial) with their runs, records and stations", run_units},
        Query{"calibrations",
              "Calibration records of every station, newest first, the one in force per unit "
              "marked",
              run_calibrations},
        Query{"parameters",
              "Each calibration parameter's distribution per station (every unit's newest "
              "record)",
              run_parameters}}) {
    auto opt = std::make_shared<FleetCliOptions>();
    auto* sub = cmd->add_subcommand(q.name, q.help);
    add_central_options(sub, opt->central, "--from", "Central database", true);
    sub->add_option("--station", opt->filter.station, "Only this station (name or uuid)");
    sub->add_option("--serial", opt->filter.serial, "Only this unit");
    sub->add_option("--since", opt->filter.since_utc,
                    "Only since this UTC date (YYYY-MM-DD) or time (YYYY-MM-DDTHH:MM[:SS])");
    sub->add_flag("--json", opt->as_json, "Print as JSON");
    auto run = q.run;
    sub->callback([opt, run] { run(*opt); });
  }
}

}  // namespace calstand::cli

// `calstand sync`: copy a station's database to the fleet's central PostgreSQL database.
#include <fmt/format.h>
#include <unistd.h>

#include <array>
#include <string>

#include "central_option.hpp"
#include "commands.hpp"
#include "fleet/sync.hpp"
#include "open_database.hpp"

namespace calstand::cli {
namespace {

struct SyncCliOptions {
  std::string db;
  CentralOptions central;
  std::string name;
  bool samples = false;
  std::size_t batch_rows = fleet::SyncOptions{}.batch_rows;
  std::size_t batch_chunks = fleet::SyncOptions{}.batch_chunks;
  bool as_json = false;
};

std::string host_name() {
  std::array<char, 256> name{};
  if (::gethostname(name.data(), name.size() - 1) != 0) return "station";
  return name.data();
}

void run_sync(const SyncCliOptions& opt) {
  fleet::SyncOptions options;
  options.station_name = opt.name.empty() ? host_name() : opt.name;
  options.samples = opt.samples;
  options.batch_rows = opt.batch_rows;
  options.batch_chunks = opt.batch_chunks;
  options.validate();
  // The address is checked before anything is opened: a password in it is refused at once.
  const fleet::CentralAddress address =
      fleet::parse_central_address(opt.central.url, opt.central.password_file, "--to");
  store::Database db = open_existing_database(opt.db);
  auto central = fleet::connect_central(address);
  const fleet::SyncReport report = fleet::sync_station(db, *central, options);
  if (opt.as_json) {
    fmt::print("{}\n", fleet::to_json(report).dump(2));
    return;
  }
  const fleet::SyncCounts& c = report.copied;
  fmt::print("station {} ({})\n", report.station_name, report.station_uuid);
  if (c.rows() == 0 && c.sample_chunks == 0) {
    fmt::print("nothing new: the central database has every ended run of this station\n");
  } else {
    fmt::print(
        "copied {} runs ({} steps, {} events, {} units, {} step means, {} table and {} chamber "
        "telemetry rows), {} station events, {} calibrations, {} acceptances, {} fits",
        c.runs, c.steps, c.events, c.run_units, c.step_means, c.table_telemetry,
        c.chamber_telemetry, c.station_events, c.calibrations, c.acceptances, c.fits);
    if (opt.samples) {
      fmt::print(", {} sample chunks ({} samples, {:.1f} MB)", c.sample_chunks, c.samples,
                 static_cast<double>(c.sample_bytes) / 1e6);
    }
    fmt::print(" in {:.2f} s\n", report.seconds);
  }
  if (!report.waiting_runs.empty()) {
    fmt::print("waiting: {} runs that have not ended (first: run {})\n", report.waiting_runs.size(),
               report.waiting_runs.front());
  }
}

}  // namespace

void register_sync(CLI::App& app) {
  auto opt = std::make_shared<SyncCliOptions>();
  auto* cmd = app.add_subcommand(
      "sync",
      "Copy this station's ended runs, records, verdicts and fits (and samples) to the fleet's "
      "central PostgreSQL database; resumes where a cut sync stopped");
  cmd->add_option("--db", opt->db, "Station database file")->required();
  add_central_options(cmd, opt->central, "--to", "Central database", true);
  cmd->add_option("--name", opt->name,
                  "Name the station registers with on its first sync (default: host name)");
  cmd->add_flag("--samples", opt->samples, "Copy the sample chunks of the runs too");
  cmd->add_option("--batch-rows", opt->batch_rows, "Rows per central transaction")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--batch-chunks", opt->batch_chunks, "Sample chunks per central transaction")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--json", opt->as_json, "Print what was copied as JSON");
  cmd->callback([opt] { run_sync(*opt); });
}

}  // namespace calstand::cli

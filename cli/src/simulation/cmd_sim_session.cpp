// `calstand sim-session`: a simulated session without a table (an IMU turned by hand between
// static poses, a record at rest, or a labelled Ferraris session), written as a calstand-import/2
// folder with its truth (sim/hand_session.hpp, sim/session_folder.hpp).
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "sim/hand_session.hpp"
#include "sim/session_folder.hpp"
#include "sim/spec_sheet.hpp"

namespace calstand::cli {
namespace {

struct SimSessionOptions {
  std::string kind = "hand";
  std::string out;
  std::uint64_t seed = 1;
  std::string model = "adis16488";
  int poses = 30;
  double rate_hz = 0.0;
  double rest_s = 50.0;
  double tilt_deg = 1.0;
  double turn_angle_deg = 360.0;
  bool counts = false;
};

sim::SessionImu session_imu(const SimSessionOptions& opt) {
  sim::SessionImu imu;
  imu.sample_rate_hz = opt.rate_hz;
  if (sim::builtin_spec(opt.model)) {
    imu.spec = opt.model;
  } else if (std::filesystem::exists(opt.model)) {
    imu.truth = sim::truth_from_spec(core::read_json_file(opt.model), opt.model, opt.seed);
  } else {
    std::string known;
    for (const auto& n : sim::builtin_spec_names()) known += (known.empty() ? "" : ", ") + n;
    throw core::InputError("--model " + opt.model,
                           fmt::format("neither a spec-sheet file nor a built-in one ({})", known));
  }
  return imu;
}

void run_sim_session(const SimSessionOptions& opt) {
  sim::SimSession s;
  if (opt.kind == "hand" || opt.kind == "static") {
    sim::HandSessionOptions o;
    o.imu = session_imu(opt);
    // A static record is a hand session that never leaves its initial rest on the bench.
    o.poses = opt.kind == "static" ? 0 : opt.poses;
    o.initial_rest_s = opt.rest_s;
    s = sim::simulate_hand_session(o, opt.seed);
  } else if (opt.kind == "ferraris") {
    sim::FerrarisSessionOptions o;
    o.imu = session_imu(opt);
    o.placement_tilt_deg = opt.tilt_deg;
    o.turn_angle_deg = opt.turn_angle_deg;
    s = sim::simulate_ferraris_session(o, opt.seed);
  } else {
    throw core::InputError("--kind", "must be hand, static or ferraris, not \"" + opt.kind + "\"");
  }
  sim::SessionFolderOptions fo;
  fo.counts = opt.counts;
  sim::write_session_folder(s, opt.out, fo);
  const double duration = s.samples.back().receive_time_s - s.samples.front().receive_time_s;
  fmt::print(
      "{} session of a simulated {} (seed {}): {} samples at {:g} Hz, {:.1f} s, {} static "
      "holds{}, {} turns\n",
      opt.kind, s.model_name, s.seed, s.samples.size(), s.sample_rate_hz, duration, s.holds.size(),
      s.kind == "hand" ? " (the first the initial rest)" : "", s.turns.size());
  fmt::print(
      "wrote {}/meta.json, samples.csv ({}), truth.json (frame: the accelerometer "
      "triad's)\n",
      opt.out, opt.counts ? "raw counts, nominal in meta.json" : "deg/s and m/s^2");
}

}  // namespace

void register_sim_session(CLI::App& app) {
  auto opt = std::make_shared<SimSessionOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sim-session",
      "Simulate a session without a table (hand-held poses, or a labelled Ferraris session) and "
      "write it as a calstand-import/2 folder with its truth");
  cmd->add_option("--kind", opt->kind,
                  "hand, static (the initial rest alone: a record at rest) or ferraris")
      ->capture_default_str();
  cmd->add_option("--out", opt->out, "Folder to write (created)")->required();
  cmd->add_option("--seed", opt->seed, "Seed of the IMU draw, the poses and the noise")
      ->capture_default_str();
  cmd->add_option("--model", opt->model, "Built-in spec (ln200, adis16488) or spec-sheet file")
      ->capture_default_str();
  cmd->add_option("--poses", opt->poses, "hand: static poses after the initial rest")
      ->capture_default_str();
  cmd->add_option("--rest", opt->rest_s, "hand and static: initial rest [s]")
      ->capture_default_str();
  cmd->add_option("--rate", opt->rate_hz, "Output rate [Hz] (0: the sheet's)")
      ->capture_default_str();
  cmd->add_option("--tilt", opt->tilt_deg, "ferraris: RMS placement tilt of each hold [deg]")
      ->capture_default_str();
  cmd->add_option("--turn-angle", opt->turn_angle_deg,
                  "ferraris: signed turn angle about each axis [deg] (+: counter-clockwise)")
      ->capture_default_str();
  cmd->add_flag("--counts", opt->counts, "Write raw 16-bit counts with a nominal conversion");
  cmd->callback([opt] { run_sim_session(*opt); });
}

}  // namespace calstand::cli

// `calstand demo`: a first look at the simulated IMU on the embedded simulator. Runs the library
// procedure `first-look` through the same run path as `calstand run` (plan, engine, store), reads
// the run back with analysis::first_look(), and prints what it measured beside the simulator's
// truth, which only a simulated station knows.
#include <fmt/format.h>
#include <stdlib.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/first_look.hpp"
#include "commands.hpp"
#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/station_config.hpp"
#include "daemon/campaign.hpp"
#include "daemon/station_run.hpp"
#include "drivers/sim_station.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"
#include "store/database_lock.hpp"
#include "store/run_store.hpp"

namespace calstand::cli {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

struct DemoOptions {
  std::string station_file;
  std::uint64_t seed = 0;
  bool seed_given = false;
  double capture_s = 10.0;
  std::string db;  ///< "" = a temporary database, removed at the end
  bool as_json = false;
};

constexpr const char* kProcedure = "first-look";
constexpr double kChamberStepC = 45.0;  // the step's setpoint, or the chamber's maximum if lower

// A temporary folder for the demo's database, removed when the demo ends however it ends.
class TemporaryFolder {
 public:
  TemporaryFolder() {
    std::string pattern = (fs::temp_directory_path() / "calstand-demo-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw std::runtime_error("cannot make a temporary folder for the demo's database in " +
                               fs::temp_directory_path().string());
    }
    path_ = pattern;
  }
  ~TemporaryFolder() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

json vec_json(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

std::string vec_text(const Eigen::Vector3d& v, const char* format) {
  return fmt::format(fmt::runtime(fmt::format("{0} {0} {0}", format)), v.x(), v.y(), v.z());
}

char axis_name(int axis) { return static_cast<char>('x' + axis); }

// What the run measured beside the simulator's truth, as JSON (also what the text shows).
json demo_json(const core::StationConfig& station, const analysis::FirstLook& look,
               sim::ImuSim& imu) {
  const sim::ImuTruth& truth = imu.truth();
  json report;
  report["station"] = station.name;
  report["run"] = look.run;
  report["imu"] = {{"name", look.device},
                   {"sample_rate_hz", truth.sample_rate_hz},
                   {"turn_on_gyro_bias_dph", vec_json(imu.turn_on_gyro_bias() * 3600.0)},
                   {"turn_on_accel_bias_mps2", vec_json(imu.turn_on_accel_bias())}};
  report["site"] = {{"latitude_deg", look.latitude_deg},
                    {"gravity_mps2", look.gravity_mps2},
                    {"earth_rate_level_dph", vec_json(look.earth_rate_level_dph)}};

  // A noise-free copy of this IMU at a table state and the temperature the capture measured,
  // so that temperature terms match too.
  auto noise_free = [&](double outer_deg, double inner_deg, double inner_rate_dps,
                        double temperature_c) {
    sim::TableKinematics k;
    k.outer_deg = outer_deg;
    k.inner_deg = inner_deg;
    k.inner_rate_dps = inner_rate_dps;
    return imu.noise_free_reading(k, temperature_c);
  };

  json positions = json::array();
  for (const auto& p : look.positions) {
    positions.push_back(
        {{"position", fmt::format("{} {}", axis_name(p.axis), p.sign > 0 ? "up" : "down")},
         {"label", p.label},
         {"step", p.step},
         {"outer_deg", p.outer_deg},
         {"inner_deg", p.inner_deg},
         {"gyro_dph", vec_json(p.gyro_dps * 3600.0)},
         {"accel_mps2", vec_json(p.accel_mps2)},
         {"noise_free_accel_mps2",
          vec_json(noise_free(p.outer_deg, p.inner_deg, 0.0, p.temperature_c).second)},
         {"temperature_c", p.temperature_c},
         {"samples", p.samples}});
  }
  report["six_position"] = positions;

  // The same two-position formulas on the noise-free readings: the pair's "bias" also holds the
  // quadratic term's g^2 share, so the truth column goes through the formula, not read off.
  json accel = json::array();
  for (const auto& a : look.accel) {
    const auto& up = look.positions[a.up];
    const auto& down = look.positions[a.down];
    const double u = noise_free(up.outer_deg, up.inner_deg, 0.0, up.temperature_c).second[a.axis];
    const double d =
        noise_free(down.outer_deg, down.inner_deg, 0.0, down.temperature_c).second[a.axis];
    accel.push_back({{"axis", std::string(1, axis_name(a.axis))},
                     {"bias_mps2", a.bias_mps2},
                     {"noise_free_bias_mps2", 0.5 * (u + d)},
                     {"scale_ppm", a.scale_ppm},
                     {"noise_free_scale_ppm", ((u - d) / (2.0 * look.gravity_mps2) - 1.0) * 1e6}});
  }
  report["accel_two_position"] = accel;

  if (look.rate_test) {
    const auto& r = *look.rate_test;
    json rows = json::array();
    for (const auto* c : {&r.positive, &r.negative}) {
      rows.push_back({{"step", c->step},
                      {"rate_dps", c->rate_dps},
                      {"gyro_dps", c->gyro_dps},
                      {"expected_dps", c->reference_dps},
                      {"samples", c->samples}});
    }
    const int i = r.body_axis;
    report["rate_test"] = {
        {"table_axis", r.table_axis},
        {"axis", std::string(1, axis_name(i))},
        {"direction", r.direction},
        {"outer_deg", r.outer_deg},
        {"inner_deg", r.inner_deg},
        {"rows", rows},
        {"gyro_scale_ppm", r.scale_ppm},
        {"true_gyro_scale_ppm", truth.gyro_scale[i]},
        {"gyro_bias_dph", r.bias_dps * 3600.0},
        {"true_gyro_bias_dph", (truth.gyro_bias[i] + imu.turn_on_gyro_bias()[i]) * 3600.0}};
  }

  json thermal = json::array();
  for (const auto& m : look.thermal) {
    thermal.push_back(
        {{"step", m.step},
         {"t_min", m.t_min},
         {"air_c", m.air_c},
         {"setpoint_c", m.setpoint_c},
         {"imu_c", m.imu_c},
         {"imu_rate_c_per_min",
          std::isfinite(m.imu_rate_c_per_min) ? json(m.imu_rate_c_per_min) : json()}});
  }
  report["thermal_step"] = thermal;
  report["simulated_s"] = look.station_time_s;
  return report;
}

void print_demo(const json& j, double capture_s, double chamber_c, double ramp_c_per_min) {
  const auto v3 = [](const json& a) {
    return Eigen::Vector3d(a[0].get<double>(), a[1].get<double>(), a[2].get<double>());
  };
  const Eigen::Vector3d earth = v3(j["site"]["earth_rate_level_dph"]);
  fmt::print(
      "calstand demo: station \"{}\", IMU \"{}\" ({:.0f} Hz), latitude {:.4f} deg, "
      "g = {:.5f} m/s^2, Earth rate N {:.3f} U {:.3f} deg/h; run {} of procedure {}\n\n",
      j["station"].get<std::string>(), j["imu"]["name"].get<std::string>(),
      j["imu"]["sample_rate_hz"].get<double>(), j["site"]["latitude_deg"].get<double>(),
      j["site"]["gravity_mps2"].get<double>(), earth.y(), earth.z(), j["run"].get<int>(),
      kProcedure);
  fmt::print("Six positions, {:.0f} s static capture each after the table settles\n", capture_s);
  fmt::print("{:<7} {:>6} {:>6}  {:>29}  {:>32}  {:>7}\n", "pos", "outer", "inner",
             "gyro x y z [deg/h]", "accel x y z [m/s^2]", "T [degC]");
  for (const auto& p : j["six_position"]) {
    fmt::print("{:<7} {:>6.1f} {:>6.1f}  {:>29}  {:>32}  {:>7.2f}\n",
               p["position"].get<std::string>(), p["outer_deg"].get<double>(),
               p["inner_deg"].get<double>(), vec_text(v3(p["gyro_dph"]), "{:9.3f}"),
               vec_text(v3(p["accel_mps2"]), "{:10.5f}"), p["temperature_c"].get<double>());
  }

  fmt::print(
      "\nAccelerometers from the up/down pairs: bias = (up + down) / 2, "
      "scale = (up - down) / 2g - 1\n");
  fmt::print("{:<5} {:>14} {:>14} {:>12} {:>12}\n", "axis", "bias [mg]", "noise-free",
             "scale [ppm]", "noise-free");
  const double mg = 1e3 / core::kStandardGravity;
  for (const auto& a : j["accel_two_position"]) {
    fmt::print("{:<5} {:>14.4f} {:>14.4f} {:>12.1f} {:>12.1f}\n", a["axis"].get<std::string>(),
               a["bias_mps2"].get<double>() * mg, a["noise_free_bias_mps2"].get<double>() * mg,
               a["scale_ppm"].get<double>(), a["noise_free_scale_ppm"].get<double>());
  }

  if (j.contains("rate_test")) {
    const auto& r = j["rate_test"];
    const std::string axis = r["axis"];
    fmt::print(
        "\nRate test about the {} axis (outer {:.1f}, inner {:.1f} deg), body axis {}{} along "
        "it, whole revolutions each way\n",
        r["table_axis"].get<std::string>(), r["outer_deg"].get<double>(),
        r["inner_deg"].get<double>(), r["direction"].get<int>() > 0 ? '+' : '-', axis);
    fmt::print("{:>10} {:>18} {:>22}\n", "rate", fmt::format("gyro {} [deg/s]", axis),
               "table+Earth [deg/s]");
    for (const auto& row : r["rows"]) {
      fmt::print("{:>10.1f} {:>18.6f} {:>22.6f}\n", row["rate_dps"].get<double>(),
                 row["gyro_dps"].get<double>(), row["expected_dps"].get<double>());
    }
    fmt::print(
        "gyro {0} scale error from CW/CCW: {1:.1f} ppm (truth {2:.1f} ppm); "
        "bias after removing Earth rate: {3:.3f} deg/h (truth {4:.3f} deg/h)\n",
        axis, r["gyro_scale_ppm"].get<double>(), r["true_gyro_scale_ppm"].get<double>(),
        r["gyro_bias_dph"].get<double>(), r["true_gyro_bias_dph"].get<double>());
  }

  fmt::print("\nChamber to {:.0f} degC at {:.1f} degC/min; the IMU follows the air with a lag\n",
             chamber_c, ramp_c_per_min);
  fmt::print("{:>8} {:>10} {:>10} {:>20}\n", "t [min]", "air [C]", "IMU [C]",
             "IMU since last [C/min]");
  for (const auto& m : j["thermal_step"]) {
    const std::string rate = m["imu_rate_c_per_min"].is_null()
                                 ? std::string("")
                                 : fmt::format("{:.3f}", m["imu_rate_c_per_min"].get<double>());
    fmt::print("{:>8.0f} {:>10.2f} {:>10.2f} {:>20}\n", m["t_min"].get<double>(),
               m["air_c"].get<double>(), m["imu_c"].get<double>(), rate);
  }
  const double sim_s = j["simulated_s"].get<double>();
  const double wall_s = j["wall_s"].get<double>();
  fmt::print("\nSimulated {:.2f} h of lab time in {:.2f} s of wall time ({:.0f}x real time).\n",
             sim_s / 3600.0, wall_s, sim_s / std::max(wall_s, 1e-9));
  if (j.contains("db"))
    fmt::print("The run is in {} (run {}).\n", j["db"].get<std::string>(), j["run"].get<int>());
}

int run_demo(const DemoOptions& opt) {
  if (!(opt.capture_s > 0.0 && opt.capture_s <= 3600.0)) {
    throw core::InputError("--capture",
                           fmt::format("must be in (0, 3600] s, got {}", opt.capture_s));
  }
  core::StationConfig station = sim::load_station_or_default(opt.station_file);
  if (opt.seed_given) station.seed = opt.seed;
  const double chamber_c = std::min(kChamberStepC, station.chamber.max_c);
  const procedures::Procedure procedure = procedures::load_procedure(kProcedure);
  const procedures::Plan plan = procedures::make_plan(
      procedure, station, {{"capture_s", opt.capture_s}, {"chamber_c", chamber_c}});
  procedures::require_valid(plan);  // e.g. a table that cannot point an axis up, before any time

  const auto wall_start = std::chrono::steady_clock::now();
  std::optional<TemporaryFolder> temporary;
  if (opt.db.empty()) temporary.emplace();
  const std::string db_path = opt.db.empty() ? (temporary->path() / "demo.db").string() : opt.db;
  const store::DatabaseLock lock(db_path, store::DatabaseLock::Mode::kShared, "calstand demo");
  std::int64_t run_id = 0;
  {
    store::Database db(db_path);
    store::RunStore runs(db);
    run_id = daemon::create_run_record(runs, station, procedure, plan);
  }
  daemon::StationRun wired(station, db_path, run_id, 0.0);
  auto* simulated = dynamic_cast<drivers::SimStation*>(&wired.station());
  if (simulated == nullptr) {
    throw core::InputError(
        "--station", fmt::format("station \"{}\" has real devices; the demo compares with the "
                                 "simulator's truth and runs on the simulator only (on real "
                                 "devices: calstand run {} --station FILE)",
                                 station.name, kProcedure));
  }
  const daemon::CampaignResult result = wired.run(plan, {}, wired.store_journal());
  if (result.state != daemon::RunState::kCompleted) {
    throw std::runtime_error(fmt::format("the demo run {} ended {}: {}", run_id,
                                         to_string(result.state), result.exit_reason));
  }

  analysis::FirstLook look = analysis::first_look(wired.database(), run_id);
  json report = demo_json(station, look, simulated->world().imu(0));
  report["wall_s"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  if (!opt.db.empty()) report["db"] = opt.db;
  if (opt.as_json) {
    fmt::print("{}\n", report.dump(2));
  } else {
    print_demo(report, opt.capture_s, chamber_c, station.chamber.max_ramp_c_per_min);
  }
  return 0;
}

}  // namespace

void register_demo(CLI::App& app) {
  auto opt = std::make_shared<DemoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "demo",
      "A first look at the simulated IMU: runs the library procedure first-look (six positions, "
      "a CW/CCW rate test, a chamber step) on the embedded simulator and compares what it "
      "measured with the simulator's truth");
  cmd->add_option("--station", opt->station_file,
                  "Simulated station file (default: built-in simulator)");
  cmd->add_option("--seed", opt->seed, "Override the station seed")
      ->each([opt](const std::string&) { opt->seed_given = true; });
  cmd->add_option("--capture", opt->capture_s, "Static capture per position [s], in (0, 3600]")
      ->capture_default_str();
  cmd->add_option("--db", opt->db,
                  "Keep the run in this SQLite file (default: a temporary one, removed)");
  cmd->add_flag("--json", opt->as_json, "Machine-readable output");
  cmd->callback([opt] { run_demo(*opt); });
}

}  // namespace calstand::cli

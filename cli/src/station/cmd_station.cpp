// `calstand station`: checks a station file (or the built-in one) and shows what calstand
// makes of it: site gravity and Earth rate, table and chamber limits, and each IMU's truth.
#include <fmt/format.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "core/rotation.hpp"
#include "core/station_config.hpp"
#include "sim/imu_truth.hpp"
#include "sim/sim_world.hpp"

namespace calstand::cli {
namespace {

struct StationOptions {
  std::string station_file;
  bool as_json = false;
};

// A per-axis figure of a truth file (a number, or [x, y, z]) as short text.
std::string figure(const nlohmann::json& v) {
  if (v.is_number()) return fmt::format("{:.4g}", v.get<double>());
  return fmt::format("[{:.4g} {:.4g} {:.4g}]", v[0].get<double>(), v[1].get<double>(),
                     v[2].get<double>());
}

void check_station(const StationOptions& opt) {
  const core::StationConfig station = sim::load_station_or_default(opt.station_file);
  const Eigen::Vector3d earth_dph =
      station.site.earth_rate_level_radps() * core::kRadToDeg * 3600.0;
  // Build each simulated IMU as the simulated world would, so that a truth the simulator
  // cannot run (not only one the schema rejects) fails here, before the station is called valid.
  nlohmann::json imus = nlohmann::json::array();
  for (std::size_t i = 0; i < station.imus.size(); ++i) {
    const auto& imu = station.imus[i];
    nlohmann::json entry = {{"name", imu.name}, {"backend", imu.backend}};
    if (imu.backend == "sim") {
      entry["truth"] = sim::imu_truth_to_json(sim::make_imu_sim(station, i)->truth());
    }
    imus.push_back(std::move(entry));
  }
  if (opt.as_json) {
    nlohmann::json out = station.to_json();
    out["derived"] = {{"gravity_mps2", station.site.gravity()},
                      {"earth_rate_enu_dph", {earth_dph.x(), earth_dph.y(), earth_dph.z()}},
                      {"imus", imus}};
    fmt::print("{}\n", out.dump(2));
    return;
  }
  fmt::print("station \"{}\" is valid{}\n", station.name,
             opt.station_file.empty() ? " (built-in)" : "");
  fmt::print("site      latitude {:.4f} deg, height {:.1f} m, g = {:.6f} m/s^2 ({})\n",
             station.site.latitude_deg, station.site.height_m, station.site.gravity(),
             station.site.gravity_mps2 ? "configured" : "WGS-84 normal gravity");
  fmt::print("          Earth rate north {:.4f} deg/h, up {:.4f} deg/h\n", earth_dph.y(),
             earth_dph.z());
  const auto& t = station.table;
  fmt::print(
      "table     {} backend; outer axis [{:g} {:g} {:g}] max {:g} deg/s, {:g} deg/s^2; "
      "inner axis [{:g} {:g} {:g}] max {:g} deg/s, {:g} deg/s^2\n",
      t.backend, t.outer_axis.x(), t.outer_axis.y(), t.outer_axis.z(), t.outer.max_rate_dps,
      t.outer.max_accel_dps2, t.inner_axis.x(), t.inner_axis.y(), t.inner_axis.z(),
      t.inner.max_rate_dps, t.inner.max_accel_dps2);
  if (!t.tilt_rad.isZero()) {
    fmt::print("          base tilt east {:g} rad, north {:g} rad\n", t.tilt_rad.x(),
               t.tilt_rad.y());
  }
  const auto& c = station.chamber;
  fmt::print(
      "chamber   {} backend; {:g} to {:g} degC, ramp up to {:g} degC/min, ambient {:g} degC\n",
      c.backend, c.min_c, c.max_c, c.max_ramp_c_per_min, c.ambient_c);
  for (const auto& entry : imus) {
    fmt::print("imu       {} ({} backend)", entry["name"].get<std::string>(),
               entry["backend"].get<std::string>());
    if (entry.contains("truth")) {
      const auto& tr = entry["truth"];
      fmt::print(": {:g} Hz, {} non-zero error parameters, ARW {} deg/sqrt(h), VRW {} m/s/sqrt(h)",
                 tr["output"]["sample_rate_hz"].get<double>(), tr["parameters"].size(),
                 figure(tr["noise"]["gyro"]["arw_deg_per_sqrt_h"]),
                 figure(tr["noise"]["accel"]["vrw_mps_per_sqrt_h"]));
    }
    fmt::print("\n");
  }
}

}  // namespace

void register_station(CLI::App& app) {
  auto opt = std::make_shared<StationOptions>();
  CLI::App* cmd = app.add_subcommand(
      "station", "Check a station file (or the built-in simulated station) and show it");
  cmd->add_option("--station", opt->station_file, "Station file (default: built-in simulator)");
  cmd->add_flag("--json", opt->as_json, "The resolved station, with each simulated IMU's truth");
  cmd->callback([opt] { check_station(*opt); });
}

}  // namespace calstand::cli

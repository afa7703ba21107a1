#include "core/station_config.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <set>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/schemas.hpp"

namespace calstand::core {
namespace {

using nlohmann::json;

Eigen::Vector3d vec3(const json& a) {
  return {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
}

json vec3_json(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

AxisConfig axis_from_json(const json& j) {
  AxisConfig a;
  a.max_rate_dps = j.at("max_rate_dps").get<double>();
  a.max_accel_dps2 = j.at("max_accel_dps2").get<double>();
  a.encoder_resolution_deg = j.value("encoder_resolution_deg", a.encoder_resolution_deg);
  a.position_tolerance_deg = j.value("position_tolerance_deg", a.position_tolerance_deg);
  a.rate_tolerance_dps = j.value("rate_tolerance_dps", a.rate_tolerance_dps);
  a.settle_time_s = j.value("settle_time_s", a.settle_time_s);
  a.servo_time_constant_s = j.value("servo_time_constant_s", a.servo_time_constant_s);
  return a;
}

json axis_to_json(const AxisConfig& a) {
  return {{"max_rate_dps", a.max_rate_dps},
          {"max_accel_dps2", a.max_accel_dps2},
          {"encoder_resolution_deg", a.encoder_resolution_deg},
          {"position_tolerance_deg", a.position_tolerance_deg},
          {"rate_tolerance_dps", a.rate_tolerance_dps},
          {"settle_time_s", a.settle_time_s},
          {"servo_time_constant_s", a.servo_time_constant_s}};
}

std::string resolve(const std::string& base_dir, const std::string& path) {
  const std::filesystem::path p(path);
  if (p.is_absolute()) return p.lexically_normal().string();
  return (std::filesystem::path(base_dir) / p).lexically_normal().string();
}

/// A device's connection with every string field named "*_file" (e.g. a CAN signal map's
/// "map_file") or "dbc" resolved against the station file's folder, as spec and truth files are.
/// A `command_set`: a built-in name as it is, a file path (one with a '/' or ending in .json)
/// resolved against the station file's folder.
std::string resolve_command_set(const std::string& name_or_path, const std::string& base_dir) {
  const bool is_path =
      name_or_path.find('/') != std::string::npos || name_or_path.ends_with(".json");
  return is_path ? resolve(base_dir, name_or_path) : name_or_path;
}

json resolve_connection_files(json connection, const std::string& base_dir) {
  if (!connection.is_object()) return connection;
  for (auto& [key, value] : connection.items()) {
    // "dbc": a CAN IMU's DBC file (docs/protocols.md, "Signals from a DBC file").
    if (value.is_string() && ((key.size() > 5 && key.ends_with("_file")) || key == "dbc")) {
      value = resolve(base_dir, value.get<std::string>());
    }
  }
  return connection;
}

// Rules the schema cannot state: checked after it, each naming its field.
void check_semantics(const StationConfig& c, const std::string& file) {
  // Axes are usually typed with a few decimals ([0.7071, 0, 0.7071]); 1e-3 accepts those and
  // still catches a vector that is not meant as a direction. from_json normalises them.
  auto unit = [&](const Eigen::Vector3d& v, const char* field) {
    if (!(std::abs(v.norm() - 1.0) <= 1e-3)) {
      throw InputError(fmt::format("{}: {}", file, field),
                       fmt::format("must be a unit vector (norm is {:.6g})", v.norm()));
    }
  };
  unit(c.table.outer_axis, "table.outer_axis");
  unit(c.table.inner_axis, "table.inner_axis");
  if (c.table.outer_axis.normalized().cross(c.table.inner_axis.normalized()).norm() < 1e-3) {
    throw InputError(fmt::format("{}: table.inner_axis", file),
                     "must not be parallel to table.outer_axis");
  }
  if (c.chamber.min_c >= c.chamber.max_c) {
    throw InputError(
        fmt::format("{}: chamber.min_c", file),
        fmt::format("{} must be below chamber.max_c {}", c.chamber.min_c, c.chamber.max_c));
  }
  if (c.chamber.ambient_c < c.chamber.min_c || c.chamber.ambient_c > c.chamber.max_c) {
    throw InputError(fmt::format("{}: chamber.ambient_c", file),
                     fmt::format("{} is outside the chamber range [{}, {}]", c.chamber.ambient_c,
                                 c.chamber.min_c, c.chamber.max_c));
  }
  // A simulated IMU needs the simulated table it sits on (one world), and a real table carries
  // real IMUs: the station is simulated or real as a whole.
  const bool simulated = c.table.backend == "sim";
  auto same_world = [&](const std::string& backend, const std::string& field) {
    if ((backend == "sim") != simulated) {
      throw InputError(fmt::format("{}: {}", file, field),
                       fmt::format("is \"{}\" but table.backend is \"{}\": a station is simulated "
                                   "(every backend \"sim\") or real (none), not a mix",
                                   backend, c.table.backend));
    }
  };
  same_world(c.chamber.backend, "chamber.backend");
  for (std::size_t i = 0; i < c.imus.size(); ++i) {
    same_world(c.imus[i].backend, fmt::format("imus[{}].backend", i));
  }
  std::set<std::string> names;
  for (std::size_t i = 0; i < c.imus.size(); ++i) {
    if (!names.insert(c.imus[i].name).second) {
      throw InputError(fmt::format("{}: imus[{}].name", file, i),
                       fmt::format("duplicate IMU name \"{}\"", c.imus[i].name));
    }
  }
  // Which IMU a supply feeds is a reference the schema cannot check; one supply per IMU, so
  // that switching "the supply of imu0" is never ambiguous.
  std::set<std::string> supply_names;
  std::set<std::string> fed;
  for (std::size_t i = 0; i < c.power_supplies.size(); ++i) {
    const PowerSupplyConfig& p = c.power_supplies[i];
    same_world(p.backend, fmt::format("power_supplies[{}].backend", i));
    if (!supply_names.insert(p.name).second) {
      throw InputError(fmt::format("{}: power_supplies[{}].name", file, i),
                       fmt::format("duplicate supply name \"{}\"", p.name));
    }
    if (!names.contains(p.imu)) {
      throw InputError(fmt::format("{}: power_supplies[{}].imu", file, i),
                       fmt::format("no IMU named \"{}\" in imus", p.imu));
    }
    if (!fed.insert(p.imu).second) {
      throw InputError(fmt::format("{}: power_supplies[{}].imu", file, i),
                       fmt::format("\"{}\" is already fed by another supply", p.imu));
    }
  }
}

}  // namespace

const PowerSupplyConfig* StationConfig::supply_of(const std::string& imu_name) const {
  for (const auto& p : power_supplies) {
    if (p.imu == imu_name) return &p;
  }
  return nullptr;
}

TableGeometry StationConfig::geometry(std::size_t imu_index) const {
  TableGeometry g;
  g.outer_axis = table.outer_axis.normalized();
  g.inner_axis = table.inner_axis.normalized();
  if (imu_index < imus.size())
    g.mount_C_PB = from_roll_pitch_yaw_deg(imus[imu_index].mount_rpy_deg);
  return g;
}

StationConfig StationConfig::from_json(const json& doc, const std::string& file_name,
                                       const std::string& base_dir) {
  validate_or_throw(schema("station.schema.json"), doc, file_name);
  StationConfig c;
  c.name = doc.at("name").get<std::string>();
  c.description = doc.value("description", std::string());
  c.seed = doc.value("seed", std::uint64_t{1});

  const json& site = doc.at("site");
  c.site.latitude_deg = site.at("latitude_deg").get<double>();
  c.site.longitude_deg = site.value("longitude_deg", 0.0);
  c.site.height_m = site.at("height_m").get<double>();
  if (site.contains("gravity_mps2")) c.site.gravity_mps2 = site.at("gravity_mps2").get<double>();

  const json& table = doc.at("table");
  c.table.backend = table.at("backend").get<std::string>();
  c.table.outer_axis = vec3(table.at("outer_axis"));
  c.table.inner_axis = vec3(table.at("inner_axis"));
  c.table.outer = axis_from_json(table.at("outer"));
  c.table.inner = axis_from_json(table.at("inner"));
  c.table.connection =
      resolve_connection_files(table.value("connection", json::object()), base_dir);
  if (table.contains("command_set")) {
    c.table.command_set = resolve_command_set(table.at("command_set").get<std::string>(), base_dir);
  }
  if (table.contains("tilt_rad")) {
    c.table.tilt_rad = {table.at("tilt_rad").value("east", 0.0),
                        table.at("tilt_rad").value("north", 0.0)};
  }

  const json& ch = doc.at("chamber");
  c.chamber.backend = ch.at("backend").get<std::string>();
  c.chamber.min_c = ch.at("min_c").get<double>();
  c.chamber.max_c = ch.at("max_c").get<double>();
  c.chamber.max_ramp_c_per_min = ch.at("max_ramp_c_per_min").get<double>();
  c.chamber.ambient_c = ch.value("ambient_c", c.chamber.ambient_c);
  if (ch.contains("sim")) {
    const json& s = ch.at("sim");
    c.chamber.air_time_constant_s = s.value("air_time_constant_s", c.chamber.air_time_constant_s);
    c.chamber.control_noise_c = s.value("control_noise_c", c.chamber.control_noise_c);
    c.chamber.control_noise_tau_s = s.value("control_noise_tau_s", c.chamber.control_noise_tau_s);
    c.chamber.imu_time_constant_s = s.value("imu_time_constant_s", c.chamber.imu_time_constant_s);
    c.chamber.imu_self_heating_c = s.value("imu_self_heating_c", c.chamber.imu_self_heating_c);
  }
  c.chamber.connection = resolve_connection_files(ch.value("connection", json::object()), base_dir);
  if (ch.contains("command_set")) {
    c.chamber.command_set = resolve_command_set(ch.at("command_set").get<std::string>(), base_dir);
  }

  for (const json& j : doc.at("imus")) {
    ImuConfig imu;
    imu.name = j.at("name").get<std::string>();
    imu.backend = j.at("backend").get<std::string>();
    imu.model = j.value("model", std::string());
    if (j.contains("spec_file")) imu.spec_file = resolve(base_dir, j.at("spec_file"));
    if (j.contains("truth_file")) imu.truth_file = resolve(base_dir, j.at("truth_file"));
    if (j.contains("truth")) imu.truth = j.at("truth");
    if (j.contains("mount_rpy_deg")) imu.mount_rpy_deg = vec3(j.at("mount_rpy_deg"));
    imu.serial = j.value("serial", std::string());
    imu.connection = resolve_connection_files(j.value("connection", json::object()), base_dir);
    c.imus.push_back(std::move(imu));
  }
  for (const json& j : doc.value("power_supplies", json::array())) {
    PowerSupplyConfig p;
    p.name = j.at("name").get<std::string>();
    p.backend = j.at("backend").get<std::string>();
    p.imu = j.at("imu").get<std::string>();
    p.voltage_v = j.at("voltage_v").get<double>();
    p.current_limit_a = j.at("current_limit_a").get<double>();
    p.safe_state = j.value("safe_state", p.safe_state);
    p.start_timeout_s = j.value("start_timeout_s", p.start_timeout_s);
    p.connection = resolve_connection_files(j.value("connection", json::object()), base_dir);
    c.power_supplies.push_back(std::move(p));
  }
  if (doc.contains("policy")) {
    const json& p = doc.at("policy");
    c.policy.on_sequence_gap = p.value("on_sequence_gap", c.policy.on_sequence_gap);
    c.policy.on_stale_stream = p.value("on_stale_stream", c.policy.on_stale_stream);
    c.policy.stale_after_s = p.value("stale_after_s", c.policy.stale_after_s);
    c.policy.capture_band_factor = p.value("capture_band_factor", c.policy.capture_band_factor);
    c.policy.max_capture_attempts = p.value("max_capture_attempts", c.policy.max_capture_attempts);
    c.policy.link_outage_s = p.value("link_outage_s", c.policy.link_outage_s);
    c.policy.min_free_disk_mb = p.value("min_free_disk_mb", c.policy.min_free_disk_mb);
    c.policy.disk_reserve_mb = p.value("disk_reserve_mb", c.policy.disk_reserve_mb);
  }
  if (doc.contains("sim")) {
    c.sim_max_step_s = doc.at("sim").value("max_step_s", c.sim_max_step_s);
    c.sim_thermal_step_s = doc.at("sim").value("thermal_step_s", c.sim_thermal_step_s);
  }
  c.time_scale = doc.value("time_scale", c.time_scale);
  c.require_serial = doc.value("require_serial", false);
  c.equipment = doc.value("equipment", json::array());
  check_semantics(c, file_name);
  c.table.outer_axis.normalize();
  c.table.inner_axis.normalize();
  return c;
}

StationConfig StationConfig::load(const std::string& path) {
  const json doc = read_json_file(path);
  const auto dir = std::filesystem::path(path).parent_path();
  return from_json(doc, path, dir.empty() ? "." : dir.string());
}

json StationConfig::to_json() const {
  json site_j = {{"latitude_deg", site.latitude_deg},
                 {"longitude_deg", site.longitude_deg},
                 {"height_m", site.height_m}};
  if (site.gravity_mps2) site_j["gravity_mps2"] = *site.gravity_mps2;
  json imus_j = json::array();
  for (const auto& imu : imus) {
    json j = {{"name", imu.name},
              {"backend", imu.backend},
              {"mount_rpy_deg", vec3_json(imu.mount_rpy_deg)}};
    if (!imu.model.empty()) j["model"] = imu.model;
    if (!imu.spec_file.empty()) j["spec_file"] = imu.spec_file;
    if (!imu.truth_file.empty()) j["truth_file"] = imu.truth_file;
    if (!imu.truth.is_null()) j["truth"] = imu.truth;
    if (!imu.serial.empty()) j["serial"] = imu.serial;
    if (!imu.connection.empty()) j["connection"] = imu.connection;
    imus_j.push_back(std::move(j));
  }
  json supplies_j = json::array();
  for (const auto& p : power_supplies) {
    json j = {{"name", p.name},
              {"backend", p.backend},
              {"imu", p.imu},
              {"voltage_v", p.voltage_v},
              {"current_limit_a", p.current_limit_a},
              {"safe_state", p.safe_state},
              {"start_timeout_s", p.start_timeout_s}};
    if (!p.connection.empty()) j["connection"] = p.connection;
    supplies_j.push_back(std::move(j));
  }
  json table_j = {{"backend", table.backend},
                  {"outer_axis", vec3_json(table.outer_axis)},
                  {"inner_axis", vec3_json(table.inner_axis)},
                  {"outer", axis_to_json(table.outer)},
                  {"inner", axis_to_json(table.inner)},
                  {"tilt_rad", {{"east", table.tilt_rad.x()}, {"north", table.tilt_rad.y()}}}};
  if (!table.connection.empty()) table_j["connection"] = table.connection;
  if (!table.command_set.empty()) table_j["command_set"] = table.command_set;
  json chamber_j = {{"backend", chamber.backend},
                    {"min_c", chamber.min_c},
                    {"max_c", chamber.max_c},
                    {"max_ramp_c_per_min", chamber.max_ramp_c_per_min},
                    {"ambient_c", chamber.ambient_c},
                    {"sim",
                     {{"air_time_constant_s", chamber.air_time_constant_s},
                      {"control_noise_c", chamber.control_noise_c},
                      {"control_noise_tau_s", chamber.control_noise_tau_s},
                      {"imu_time_constant_s", chamber.imu_time_constant_s},
                      {"imu_self_heating_c", chamber.imu_self_heating_c}}}};
  if (!chamber.connection.empty()) chamber_j["connection"] = chamber.connection;
  if (!chamber.command_set.empty()) chamber_j["command_set"] = chamber.command_set;
  json doc = {{"format", "calstand-station/1"},
              {"name", name},
              {"seed", seed},
              {"site", site_j},
              {"table", table_j},
              {"chamber", chamber_j},
              {"imus", imus_j},
              {"require_serial", require_serial},
              {"equipment", equipment},
              {"policy",
               {{"on_sequence_gap", policy.on_sequence_gap},
                {"on_stale_stream", policy.on_stale_stream},
                {"stale_after_s", policy.stale_after_s},
                {"capture_band_factor", policy.capture_band_factor},
                {"max_capture_attempts", policy.max_capture_attempts},
                {"link_outage_s", policy.link_outage_s},
                {"min_free_disk_mb", policy.min_free_disk_mb},
                {"disk_reserve_mb", policy.disk_reserve_mb}}},
              {"sim", {{"max_step_s", sim_max_step_s}, {"thermal_step_s", sim_thermal_step_s}}}};
  if (!description.empty()) doc["description"] = description;
  if (time_scale != 1.0) doc["time_scale"] = time_scale;
  if (!power_supplies.empty()) doc["power_supplies"] = supplies_j;
  return doc;
}

}  // namespace calstand::core

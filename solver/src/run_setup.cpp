#include "solver/run_setup.hpp"

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/rotation.hpp"

namespace calstand::solver {
namespace {

Eigen::Vector3d vector3(const nlohmann::json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() ||
      !j[2].is_number()) {
    throw core::InputError(where, "expected an array of three numbers");
  }
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

}  // namespace

UnitIdentity unit_identity(const store::RunRecord& run, const std::string& device) {
  UnitIdentity unit;
  const nlohmann::json& snap = run.station_snapshot;
  if (snap.is_object()) {
    bool named = false;
    for (const auto& imu : snap.value("imus", nlohmann::json::array())) {
      if (imu.value("name", "") != device) continue;
      unit = {imu.value("model", ""), imu.value("serial", "")};
      named = true;
    }
    const nlohmann::json imu = snap.value("imu", nlohmann::json::object());
    if (!named && imu.is_object()) unit = {imu.value("model", ""), imu.value("serial", "")};
  }
  // The unit recorded for the run (read from the device, or given with it) is who was measured.
  for (const store::RunUnit& recorded : run.units) {
    if (recorded.imu != device) continue;
    if (!recorded.model.empty()) unit.model = recorded.model;
    unit.serial = recorded.serial;
  }
  return unit;
}

RunSetup run_setup(const store::RunRecord& run, std::int64_t run_id, const std::string& device) {
  const nlohmann::json& snap = run.station_snapshot;
  const std::string where = fmt::format("run {} station snapshot", run_id);
  RunSetup setup;
  setup.run = run_id;
  setup.device = device;
  setup.procedure_name = run.summary.procedure_name;
  setup.procedure_sha256 = run.procedure_sha256;
  if (!snap.is_object() || !snap.contains("site") || !snap.contains("table")) {
    throw core::InputError(where, "has no site or table: the run cannot be analysed");
  }
  const nlohmann::json& site = snap["site"];
  setup.site.latitude_deg = site.value("latitude_deg", 0.0);
  setup.site.longitude_deg = site.value("longitude_deg", 0.0);
  setup.site.height_m = site.value("height_m", 0.0);
  if (site.contains("gravity_mps2") && site["gravity_mps2"].is_number()) {
    setup.site.gravity_mps2 = site["gravity_mps2"].get<double>();
  }
  setup.geometry.outer_axis =
      vector3(snap["table"].value("outer_axis", nlohmann::json()), where + ": table.outer_axis")
          .normalized();
  setup.geometry.inner_axis =
      vector3(snap["table"].value("inner_axis", nlohmann::json()), where + ": table.inner_axis")
          .normalized();
  setup.temperature_ref_c = snap.value("temperature_ref_c", 25.0);
  if (snap.contains("mount_rpy_deg")) {  // calstand-import/1
    setup.geometry.mount_C_PB =
        core::from_roll_pitch_yaw_deg(vector3(snap["mount_rpy_deg"], where + ": mount_rpy_deg"));
  }
  setup.station = snap.value("name", "");
  const UnitIdentity unit = unit_identity(run, device);
  setup.imu_model = unit.model;
  setup.imu_serial = unit.serial;
  for (const auto& imu : snap.value("imus", nlohmann::json::array())) {
    if (imu.value("name", "") != device) continue;
    if (imu.contains("mount_rpy_deg")) {
      setup.geometry.mount_C_PB = core::from_roll_pitch_yaw_deg(
          vector3(imu["mount_rpy_deg"], where + ": imus." + device + ".mount_rpy_deg"));
    }
    if (imu.contains("temperature_ref_c") && imu["temperature_ref_c"].is_number()) {
      setup.temperature_ref_c = imu["temperature_ref_c"].get<double>();
    }
  }
  return setup;
}

}  // namespace calstand::solver

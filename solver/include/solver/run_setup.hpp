#pragma once

#include <cstdint>
#include <string>

#include "core/site.hpp"
#include "core/table_geometry.hpp"
#include "store/records.hpp"

namespace calstand::solver {

/// What the solver needs to know about where and how a run was recorded: the site (gravity and
/// Earth rate), the table axes with the IMU's mount, the reference temperature, and the
/// identity of the device and station (for calibration records).
struct RunSetup {
  std::int64_t run = 0;
  std::string device;      ///< samples' device name, e.g. "imu0"
  std::string imu_model;   ///< e.g. "ln200" ("" when unknown)
  std::string imu_serial;  ///< "" when the station file does not give one
  std::string station;     ///< station name ("" for an imported run)
  std::string procedure_name;
  std::string procedure_sha256;
  core::Site site;
  core::TableGeometry geometry;     ///< mount C_PB of `device` included
  double temperature_ref_c = 25.0;  ///< T_ref of dT = T - T_ref [degC]
};

/// Which unit a device of a run was: its model and serial ("" where not known).
struct UnitIdentity {
  std::string model;
  std::string serial;
};

/// The unit `device` was in `run`: as recorded with the run (read from the device, or given
/// with it), else as its snapshot names it (a station snapshot's "imus", an import's "imu").
/// Needs neither site nor table: a record without a table has a unit too.
UnitIdentity unit_identity(const store::RunRecord& run, const std::string& device);

/// Reads the setup from a run's station snapshot (a calstand-station/1 document for recorded
/// runs, the calstand-import/1 meta.json for imported ones). Throws core::InputError naming the
/// run and field when the snapshot lacks what the solver needs.
RunSetup run_setup(const store::RunRecord& run, std::int64_t run_id, const std::string& device);

}  // namespace calstand::solver

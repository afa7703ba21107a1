#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/site.hpp"
#include "core/table_geometry.hpp"

namespace calstand::core {

/// Limits and servo figures of one table axis (schemas/station.schema.json, `$defs/axis`).
struct AxisConfig {
  double max_rate_dps = 300.0;           ///< |rate| never exceeds this [deg/s]
  double max_accel_dps2 = 200.0;         ///< |acceleration| never exceeds this [deg/s^2]
  double encoder_resolution_deg = 1e-4;  ///< reported angles are multiples of this [deg]
  double position_tolerance_deg = 1e-3;  ///< in position when |error| stays below this [deg]
  double rate_tolerance_dps = 1e-3;      ///< rate settled when |rate error| below this [deg/s]
  double settle_time_s = 0.5;            ///< the error must stay in tolerance this long [s]
  double servo_time_constant_s = 0.05;   ///< simulator only: servo lag behind the profile [s]
};

struct TableConfig {
  std::string backend = "sim";
  Eigen::Vector3d outer_axis{0.0, 1.0, 0.0};  ///< unit, in L (normalised on load)
  Eigen::Vector3d inner_axis{0.0, 0.0, 1.0};  ///< unit, in L at outer = 0 (normalised on load)
  /// True tilt of the table base about L's East (x) and North (y) axes [rad]: the contract's
  /// `table_tilt` term. A property of the station, not of an IMU; zero unless configured.
  Eigen::Vector2d tilt_rad = Eigen::Vector2d::Zero();
  AxisConfig outer;
  AxisConfig inner;
  nlohmann::json connection = nlohmann::json::object();
  /// A built-in command set's name or a command-set file's absolute path; empty: the backend's
  /// own (docs/protocols.md, Command sets).
  std::string command_set;
};

struct ChamberConfig {
  std::string backend = "sim";
  double min_c = -55.0;
  double max_c = 125.0;
  double max_ramp_c_per_min = 5.0;
  double ambient_c = 23.0;
  // Simulator thermal model (see sim::ChamberParams).
  double air_time_constant_s = 90.0;
  double control_noise_c = 0.02;
  double control_noise_tau_s = 20.0;
  double imu_time_constant_s = 600.0;
  double imu_self_heating_c = 3.0;
  nlohmann::json connection = nlohmann::json::object();
  /// A built-in command set's name or a command-set file's absolute path; empty: the backend's
  /// own (docs/protocols.md, Command sets).
  std::string command_set;
};

/// One IMU of the station. Exactly one truth source is set for a simulated IMU.
struct ImuConfig {
  std::string name;
  std::string backend = "sim";
  std::string model;       ///< built-in spec sheet name ("ln200", "adis16488")
  std::string spec_file;   ///< absolute path (resolved against the station file)
  std::string truth_file;  ///< absolute path
  nlohmann::json truth;    ///< inline truth document, or null
  Eigen::Vector3d mount_rpy_deg = Eigen::Vector3d::Zero();
  /// The unit's serial number, or empty. A simulated IMU reports it as a device whose protocol
  /// carries its identity would; for a real IMU whose protocol cannot, it names the unit that
  /// stays in this slot (a lab). A factory gives each run's units with `--unit NAME=SN`.
  std::string serial;
  nlohmann::json connection = nlohmann::json::object();
};

/// A programmable supply feeding one IMU (station file `power_supplies[]`). The engine switches
/// it for `power` steps; make_safe() leaves it per `safe_state`.
struct PowerSupplyConfig {
  std::string name;
  std::string backend = "sim";   ///< "sim" (the in-process simulator) or "scpi"
  std::string imu;               ///< the name of the IMU it feeds (one supply per IMU)
  double voltage_v = 28.0;       ///< output voltage set at configure() [V]
  double current_limit_a = 1.0;  ///< current limit set at configure() [A]
  /// What the safe state does with the output: "off" switches it off, "on" leaves it as it is
  /// (a unit that must stay warm, or whose heaters must not cycle).
  std::string safe_state = "off";
  /// After the supply switches its unit on, the unit's stream must start within this, or the
  /// run fails to the safe state: the unit's boot time plus margin (a navigation-grade unit
  /// aligning its gyros may take minutes) [s].
  double start_timeout_s = 10.0;
  nlohmann::json connection = nlohmann::json::object();
};

/// How the run engine treats stream faults and invalid captures (station file `policy`).
struct FaultPolicy {
  /// "record" (event, keep the capture), "repeat_capture" or "abort".
  std::string on_sequence_gap = "record";
  std::string on_stale_stream = "repeat_capture";
  double stale_after_s = 1.0;        ///< silence that makes a stream stale [s]
  double capture_band_factor = 2.0;  ///< band = factor * soak tolerance around the setpoint
  int max_capture_attempts = 3;
  /// A table or chamber link that drops (the controller unreadable, not faulted) is ridden
  /// out for this long, recorded; longer, the run aborts to the safe state [s].
  double link_outage_s = 5.0;
  /// A run starts (or resumes) only with this much free on the database's filesystem; the
  /// daemon keeps queued runs waiting until there is [MB].
  double min_free_disk_mb = 64.0;
  /// Kept in a reserve file beside the database while a run goes, and given back when the disk
  /// fills, so that the run's end (interrupted, and why) can still be written [MB].
  double disk_reserve_mb = 4.0;
};

/// A whole station: site, table, chamber, IMUs and the simulator's settings.
struct StationConfig {
  std::string name = "sim-station";
  std::string description;
  std::uint64_t seed = 1;
  Site site;
  TableConfig table;
  ChamberConfig chamber;
  std::vector<ImuConfig> imus;
  /// The supplies the station switches (at most one per IMU); empty: the IMUs are powered by
  /// something the station does not control.
  std::vector<PowerSupplyConfig> power_supplies;
  /// The supply feeding IMU `imu_name`, or nullptr.
  const PowerSupplyConfig* supply_of(const std::string& imu_name) const;
  /// The station's own measuring equipment and its calibration status (station file
  /// `equipment`: [{"name", "id", "calibrated", "due", "certificate"}], dates YYYY-MM-DD), as a
  /// unit's certificate states it: the traceability of the unit's calibration.
  nlohmann::json equipment = nlohmann::json::array();
  /// A production station: every unit of a run must have a serial (read from the device,
  /// given with the run, or fixed here), or the run is refused.
  bool require_serial = false;
  FaultPolicy policy;
  /// Station seconds per wall-clock second of a real station's clock (1 in a lab). Only for
  /// rehearsing against an accelerated `calstand sim-station`, whose world runs this much
  /// faster than the wall clock.
  double time_scale = 1.0;
  double sim_max_step_s = 0.01;
  double sim_thermal_step_s = 0.1;

  /// True when every device is simulated in process ("sim"); false when none is. A station is
  /// one or the other: from_json() refuses a mix (a simulated IMU cannot sit on a real table).
  bool is_simulated() const { return table.backend == "sim"; }

  /// The table geometry with the mount of IMU `imu_index`.
  TableGeometry geometry(std::size_t imu_index) const;

  /// The JSON a station file holds (paths as resolved); from_json(to_json()) is identity.
  nlohmann::json to_json() const;

  /// Parses and validates a station document; every schema violation is listed in the thrown
  /// SchemaError, other rule breaks (e.g. min_c >= max_c, non-unit axes, duplicate IMU names)
  /// in an InputError naming the field. Relative paths resolve against `base_dir`.
  static StationConfig from_json(const nlohmann::json& doc, const std::string& file_name,
                                 const std::string& base_dir = ".");
  /// Reads a station file (paths relative to its folder).
  static StationConfig load(const std::string& path);
};

}  // namespace calstand::core

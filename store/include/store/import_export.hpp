#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "store/database.hpp"

namespace calstand::store {

/// What import_run() created.
struct ImportResult {
  std::int64_t run = 0;     ///< the new run's id
  std::size_t steps = 0;    ///< one per distinct `step` value of samples.csv (1 without step)
  std::size_t samples = 0;  ///< data rows of samples.csv
};

/// Options of import_run().
struct ImportRunOptions {
  /// Rows per batch parsed and written.
  std::size_t batch = 8192;
  /// Called after each batch with the fraction of samples.csv read and the samples so far.
  std::function<void(double fraction, std::uint64_t samples)> progress;
};

/// Imports a `calstand-import/1` or `calstand-import/2` folder (meta.json + samples.csv, see
/// ../shared/docs/error-model.md) as a new run with status 'imported' and procedure name the
/// format.
///
/// meta.json is validated against schemas/import-meta.schema.json (/1: fixed units; any other
/// value is an error naming the field) or schemas/import-meta-2.schema.json (/2), unit-vector
/// axes, and /2's rules between fields, and samples.csv's header against it, before anything
/// is written. Then samples.csv streams through one transaction in batches (memory independent
/// of its length; parsing on a thread of its own, ahead of the writes), every row checked as it
/// comes (column count, finite numbers, integer step): the run, one completed step per distinct
/// step value (in order of first appearance; a value that comes back later in the file joins
/// its step), the samples of device "imu0" in exact (float64) chunks, the table state of every
/// row when there are table columns, and the step means. A refusal anywhere, also at the last
/// row, rolls the whole transaction back: nothing partial is written.
///
/// /1: the exact header `t,step,outer_deg,...,az`. Commanded state per step: `import_step`,
/// then `"mode": "position"` with the mean angles, or `"mode": "rate"` (a mean axis rate of at
/// least 1e-3 deg/s) with the rates and start angles; label "step N".
///
/// /2 (what the contract leaves open is decided here, for a lab engineer's expectations):
/// - samples.csv: `t,gx,gy,gz,ax,ay,az` required; `step`, the four table columns (all or none)
///   and `temp_c` optional; any order; any other column, or one named twice, is an error.
/// - Units: samples are stored in deg/s and m/s^2. `rad/s` x 180/pi; `g` is standard gravity
///   g0 = 9.80665 m/s^2 (not the site's); `counts` through meta.json's `nominal`:
///   (counts - offset_counts) / counts_per_dps (or counts_per_mps2), per axis. A fit of such a
///   run is relative to that nominal (bias in deg/s, scale in ppm of the nominal).
/// - `nominal.gyro` is required for gyro counts and refused otherwise (accel alike);
///   `site.gravity_mps2` is required without `table`; `units.angle`/`units.rate` come with
///   `table` only, `units.temperature` with a temp_c column only; `table` and the table
///   columns come together (either alone is an error naming both); `mount_rpy_deg` only with
///   `table`.
/// - Without temp_c the samples' temperature is NaN (the step means' NULL).
/// - With table columns: as /1 (above). With table columns but no step: one step "recording",
///   `{"mode": "recording"}`, the table state of every sample stored.
/// - Without table (the orientation is not known): no table rows; StepData::table reads NaN
///   and orientation_known() (store/step_data.hpp) is false. Without step: one step labelled
///   "recording", commanded `{"mode": "recording", "orientation": "unknown"}` (a static-interval
///   detector finds the poses at fit time). With step: one step per step value, label
///   "step N", commanded `{"import_step": N, "mode": "recording", "orientation": "unknown"}`.
/// - `sections` (a calstand extension of /2 for labelled sessions such as imucal's Ferraris
///   sessions; only without `table`, and only with a step column): keys are step values, each
///   `{"label": "x_p", "kind": "static", "up": "+x"}` (the body axis pointing up) or
///   `{"label": "x_rot", "kind": "turn", "axis": "+x", "angle_deg": 360}` (turned about the body
///   axis, the sign giving the sense by the right hand). Labels are unique; every key must name
///   a step that has samples. The step's label is the section label, its commanded state
///   `{"import_step": N, "mode": "static"|"turn", "orientation": "unknown", "section": {...}}`.
///   Steps without a section stay "step N".
///
/// Throws core::InputError naming the file and the field (`meta.json: units.gyro: ...`) or the
/// line and column (`samples.csv:12: column gx: ...`); nothing is written then. Throws
/// StoreError when writing fails (the transaction is rolled back).
ImportResult import_run(Database& db, const std::filesystem::path& dir,
                        const ImportRunOptions& options = {});

/// The samples device name import_run() uses.
inline constexpr const char* kImportDevice = "imu0";

/// Options of export_run().
struct ExportOptions {
  /// IMU to export; empty: the run's only IMU with samples (an error when it has several).
  std::string device;
};

/// Writes run `run` as a `calstand-import/1` folder `out_dir`, or as a `calstand-import/2` one
/// for a run imported from /2 (its meta.json with units deg/s and m/s^2 and no nominal, since
/// the samples were converted on import; the columns its import had) (created when absent;
/// meta.json and samples.csv overwritten). Completed steps in index order, the samples of their
/// data attempt; every number printed with 17 significant digits so that exporting an imported
/// export reproduces samples.csv byte for byte. The table columns come from the table state
/// stored per sample (imported runs) or are interpolated from the run's table telemetry
/// (recorded runs, falling back to the commanded state). For an imported run meta.json is the
/// imported one; otherwise it is built from the run's station snapshot.
///
/// Throws core::InputError for an unknown run or device, StoreError when reading fails, and
/// std::runtime_error naming the file when it cannot be written.
void export_run(Database& db, std::int64_t run, const std::filesystem::path& out_dir,
                const ExportOptions& options = {});

/// Writes the samples of one IMU of run `run` (completed steps in index order) as an MCAP file
/// (docs/import.md): schema sensor_msgs/msg/Imu (ros2msg), channel /imu/data (cdr), zstd
/// chunks with CRC, a summary with statistics. Each message: header stamp = the sample's time
/// (seconds split into sec and nanosec, rounded to the nanosecond), frame_id "imu",
/// orientation unknown (covariance[0] = -1, REP 145), angular_velocity in rad/s,
/// linear_acceleration in m/s^2, covariances zero (not known). Written to `FILE.part`, renamed
/// when whole. Throws as export_run().
void export_run_mcap(Database& db, std::int64_t run, const std::filesystem::path& file,
                     const ExportOptions& options = {});

}  // namespace calstand::store

#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "store/database.hpp"

namespace calstand::store {

/// What import_run() created.
struct ImportResult {
  std::int64_t run = 0;     ///< the new run's id
  std::size_t steps = 0;    ///< one per distinct `step` value of samples.csv
  std::size_t samples = 0;  ///< data rows of samples.csv
};

/// Imports a `calstand-import/1` folder (meta.json + samples.csv, see
/// ../shared/docs/error-model.md) as a new run with status 'imported'.
///
/// Everything is validated before anything is written: meta.json against
/// schemas/import-meta.schema.json (fixed units; any other value is an error naming the field)
/// and unit-vector axes; samples.csv's exact header and every row (column count, finite
/// numbers, integer step). Then one transaction writes the run, one completed step per
/// distinct step value (in order of first appearance; commanded state: fixed position, or
/// constant rate when a mean axis rate reaches 1e-3 deg/s), the samples of device "imu0" in
/// exact (float64) chunks, the table state of every row, and the step means.
///
/// Throws core::InputError naming the file and the field (`meta.json: units.gyro: ...`) or the
/// line and column (`samples.csv:12: column gx: ...`); nothing is written then. Throws
/// StoreError when writing fails (the transaction is rolled back).
ImportResult import_run(Database& db, const std::filesystem::path& dir);

/// The samples device name import_run() uses.
inline constexpr const char* kImportDevice = "imu0";

/// Options of export_run().
struct ExportOptions {
  /// IMU to export; empty: the run's only IMU with samples (an error when it has several).
  std::string device;
};

/// Writes run `run` as a `calstand-import/1` folder `out_dir` (created when absent; meta.json
/// and samples.csv overwritten). Completed steps in index order, the samples of their data
/// attempt; every number printed with 17 significant digits so that exporting an imported
/// export reproduces samples.csv byte for byte. The table columns come from the table state
/// stored per sample (imported runs) or are interpolated from the run's table telemetry
/// (recorded runs, falling back to the commanded state). For an imported run meta.json is the
/// imported one; otherwise it is built from the run's station snapshot.
///
/// Throws core::InputError for an unknown run or device, StoreError when reading fails, and
/// std::runtime_error naming the file when it cannot be written.
void export_run(Database& db, std::int64_t run, const std::filesystem::path& out_dir,
                const ExportOptions& options = {});

}  // namespace calstand::store

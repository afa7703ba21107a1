#pragma once
// Private: reading and validating the two files of a calstand-import/1 or /2 folder.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::store::detail {

/// The exact first line of a /1 samples.csv, and the column order export writes for /2.
inline constexpr std::string_view kImportCsvHeader =
    "t,step,outer_deg,inner_deg,outer_rate_dps,inner_rate_dps,temp_c,gx,gy,gz,ax,ay,az";
inline constexpr std::string_view kImportFormat = "calstand-import/1";
inline constexpr std::string_view kImportFormat2 = "calstand-import/2";
/// The four table columns of samples.csv, all or none in /2.
inline constexpr std::array<std::string_view, 4> kTableColumns = {
    "outer_deg", "inner_deg", "outer_rate_dps", "inner_rate_dps"};

/// A labelled section of a session without table (meta.json "sections", a calstand extension
/// of /2).
struct ImportSection {
  std::string label;
  std::string kind;        ///< "static" or "turn"
  std::string up;          ///< static: the body axis pointing up, "+x" ... "-z"
  std::string axis;        ///< turn: the body axis turned about, "+x" ... "-z"
  double angle_deg = 0.0;  ///< turn: the angle turned [deg]
  nlohmann::json to_json() const;
};

/// meta.json, validated, with what reading samples.csv needs.
struct ImportMeta {
  nlohmann::json doc;
  std::string text;  ///< the file's exact text
  int version = 1;   ///< 1 or 2
  bool has_table = true;
  std::string gyro_unit = "deg/s";   ///< deg/s, rad/s or counts
  std::string accel_unit = "m/s^2";  ///< m/s^2, g or counts
  bool has_temperature_unit = true;
  bool has_angle_units = true;  ///< units.angle and units.rate
  Eigen::Vector3d gyro_offset_counts = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_counts_per_dps = Eigen::Vector3d::Ones();
  Eigen::Vector3d accel_offset_counts = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_counts_per_mps2 = Eigen::Vector3d::Ones();
  std::map<std::int64_t, ImportSection> sections;  ///< by step value
};

/// One data row of samples.csv, converted to the store's units (deg/s, m/s^2). Absent
/// columns read NaN (table columns, temp_c); without a step column every row has step 0.
struct ImportRow {
  double t_s = 0.0;
  std::int64_t step = 0;
  std::size_t line = 0;  ///< 1-based line in samples.csv
  double outer_deg = 0.0;
  double inner_deg = 0.0;
  double outer_rate_dps = 0.0;
  double inner_rate_dps = 0.0;
  double temp_c = 0.0;
  Eigen::Vector3d gyro_dps = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();
};

/// Reads and validates meta.json at `path` (its own rules only; those between meta.json and
/// samples.csv are checked by read_import_samples()). Throws core::InputError (SchemaError for
/// schema violations, listing all) naming the file and field.
ImportMeta read_import_meta(const std::filesystem::path& path);

/// samples.csv read front to back in batches and validated against its meta.json as it goes
/// (memory independent of the file's length). Errors are core::InputError whose where() is
/// `FILE:LINE` and whose message names the column, or (a rule between the two files) names
/// meta.json's field: the header's at construction, a row's when read() reaches it, and those
/// about the whole file (no samples; a section whose step has none) when read() reaches the end.
class ImportSampleReader {
 public:
  /// Opens `path` and checks its header against `meta`.
  ImportSampleReader(const std::filesystem::path& path, const ImportMeta& meta,
                     std::filesystem::path meta_path);
  ~ImportSampleReader();
  ImportSampleReader(const ImportSampleReader&) = delete;
  ImportSampleReader& operator=(const ImportSampleReader&) = delete;

  bool has_step() const { return has_step_; }
  bool has_table() const { return has_table_; }
  bool has_temperature() const { return has_temperature_; }
  /// The file name as in messages.
  const std::string& file() const;

  /// Replaces `batch` with the next rows, at most `max`; false (and `batch` empty) at the end,
  /// once the checks of the whole file have passed.
  bool read(std::vector<ImportRow>& batch, std::size_t max);
  /// Fraction of the file read, in [0, 1].
  double progress() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  bool has_step_ = true;
  bool has_table_ = true;
  bool has_temperature_ = true;
};

}  // namespace calstand::store::detail

#pragma once
// Private: reading and validating the two files of a calstand-import/1 folder.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::store::detail {

/// The exact first line of samples.csv.
inline constexpr std::string_view kImportCsvHeader =
    "t,step,outer_deg,inner_deg,outer_rate_dps,inner_rate_dps,temp_c,gx,gy,gz,ax,ay,az";
inline constexpr std::string_view kImportFormat = "calstand-import/1";

/// meta.json, validated.
struct ImportMeta {
  nlohmann::json doc;
  std::string text;  ///< the file's exact text
};

/// One data row of samples.csv, units as in the header.
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

/// Reads and validates meta.json at `path`. Throws core::InputError (SchemaError for schema
/// violations, listing all) naming the file and field.
ImportMeta read_import_meta(const std::filesystem::path& path);

/// Reads and validates samples.csv at `path`. Throws core::InputError whose where() is
/// `FILE:LINE` and whose message names the column.
std::vector<ImportRow> read_import_samples(const std::filesystem::path& path);

}  // namespace calstand::store::detail

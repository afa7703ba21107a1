#include "import_format.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <set>
#include <system_error>
#include <tuple>

#include "core/csv_reader.hpp"
#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"

namespace calstand::store::detail {
namespace {

// Standard gravity: the unit "g" of units.accel (error-model.md: g0 = 9.80665 m/s^2).
constexpr double kG0 = 9.80665;

void check_unit_vector(const nlohmann::json& v, const std::string& file, const char* field) {
  const Eigen::Vector3d a(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
  if (std::abs(a.norm() - 1.0) > 1e-6) {
    throw core::InputError(fmt::format("{}: {}", file, field),
                           fmt::format("must be a unit vector (norm is {:.6g})", a.norm()));
  }
}

Eigen::Vector3d vec3(const nlohmann::json& v) {
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

// The rules of /2 between fields of meta.json. A schema could reject most of these combinations
// but not say why (it would report "no value is allowed here"), so they are checked by hand and
// each message names the field and the rule.
void check_meta_2(ImportMeta& meta, const std::string& file) {
  const nlohmann::json& d = meta.doc;
  const auto at = [&](const std::string& field) { return fmt::format("{}: {}", file, field); };
  const nlohmann::json& units = d["units"];
  const nlohmann::json nominal = d.value("nominal", nlohmann::json::object());
  meta.has_table = d.contains("table");
  meta.gyro_unit = units["gyro"].get<std::string>();
  meta.accel_unit = units["accel"].get<std::string>();
  meta.has_temperature_unit = units.contains("temperature");
  meta.has_angle_units = units.contains("angle") || units.contains("rate");

  for (const auto& [sensor, unit, per] :
       {std::tuple{"gyro", meta.gyro_unit, "counts_per_dps"},
        std::tuple{"accel", meta.accel_unit, "counts_per_mps2"}}) {
    const bool counts = unit == "counts";
    if (counts && !nominal.contains(sensor)) {
      throw core::InputError(
          at(fmt::format("nominal.{}", sensor)),
          fmt::format("required when units.{} is 'counts' (offset_counts and {} from the "
                      "datasheet convert the counts to physical units)",
                      sensor, per));
    }
    if (!counts && nominal.contains(sensor)) {
      throw core::InputError(
          at(fmt::format("nominal.{}", sensor)),
          fmt::format("only for units.{} 'counts', but units.{} is '{}'", sensor, sensor, unit));
    }
  }
  if (nominal.contains("gyro")) {
    meta.gyro_offset_counts = vec3(nominal["gyro"]["offset_counts"]);
    meta.gyro_counts_per_dps = vec3(nominal["gyro"]["counts_per_dps"]);
  }
  if (nominal.contains("accel")) {
    meta.accel_offset_counts = vec3(nominal["accel"]["offset_counts"]);
    meta.accel_counts_per_mps2 = vec3(nominal["accel"]["counts_per_mps2"]);
  }

  if (meta.has_table) {
    check_unit_vector(d["table"]["outer_axis"], file, "table.outer_axis");
    check_unit_vector(d["table"]["inner_axis"], file, "table.inner_axis");
    for (const char* u : {"angle", "rate"}) {
      if (!units.contains(u)) {
        throw core::InputError(at(fmt::format("units.{}", u)),
                               "required with table (the table columns' unit)");
      }
    }
  } else {
    if (!d["site"].contains("gravity_mps2")) {
      throw core::InputError(at("site.gravity_mps2"),
                             "required without table (calibration by the gravity norm needs the "
                             "local gravity)");
    }
    for (const char* u : {"angle", "rate"}) {
      if (units.contains(u)) {
        throw core::InputError(at(fmt::format("units.{}", u)),
                               "only with table (and its table columns)");
      }
    }
    if (d.contains("mount_rpy_deg")) {
      throw core::InputError(at("mount_rpy_deg"),
                             "only with table (the mount is the IMU's rotation on the table)");
    }
  }

  if (d.contains("sections")) {
    if (meta.has_table) {
      throw core::InputError(at("sections"),
                             "only without table (with a table its encoders give the orientation)");
    }
    std::map<std::string, std::string> labels;  // label -> key
    for (const auto& [key, s] : d["sections"].items()) {
      const std::int64_t step = std::stoll(key);
      ImportSection section;
      section.label = s["label"].get<std::string>();
      section.kind = s["kind"].get<std::string>();
      section.up = s.value("up", "");
      section.axis = s.value("axis", "");
      section.angle_deg = s.value("angle_deg", 0.0);
      if (auto [it, fresh] = labels.emplace(section.label, key); !fresh) {
        throw core::InputError(
            at(fmt::format("sections[\"{}\"].label", key)),
            fmt::format("'{}' is also the label of section {}", section.label, it->second));
      }
      if (!meta.sections.emplace(step, section).second) {
        throw core::InputError(at(fmt::format("sections[\"{}\"]", key)),
                               fmt::format("step {} has a section already", step));
      }
    }
  }
}

// Column indices of a /2 samples.csv; none for an absent optional column.
struct Columns2 {
  std::size_t t = 0;
  std::optional<std::size_t> step, temp;
  std::array<std::size_t, 3> gyro{}, accel{};
  std::optional<std::array<std::size_t, 4>> table;
};

Columns2 map_columns_2(const core::CsvReader& csv) {
  static const std::set<std::string_view> known = {"t",
                                                   "step",
                                                   "outer_deg",
                                                   "inner_deg",
                                                   "outer_rate_dps",
                                                   "inner_rate_dps",
                                                   "temp_c",
                                                   "gx",
                                                   "gy",
                                                   "gz",
                                                   "ax",
                                                   "ay",
                                                   "az"};
  const std::string where = csv.file() + ":1";
  csv.require_unique_columns();
  for (const std::string& c : csv.columns()) {
    if (!known.contains(c)) {
      throw core::InputError(where, fmt::format("column '{}' is not a column of "
                                                "calstand-import/2 ({})",
                                                c, kImportCsvHeader));
    }
  }
  const auto required = [&](std::string_view name) {
    const auto i = csv.column(name);
    if (!i) {
      throw core::InputError(where, fmt::format("column {} is missing (t, gx, gy, gz, ax, ay and "
                                                "az are required)",
                                                name));
    }
    return *i;
  };
  Columns2 c;
  c.t = required("t");
  c.gyro = {required("gx"), required("gy"), required("gz")};
  c.accel = {required("ax"), required("ay"), required("az")};
  c.step = csv.column("step");
  c.temp = csv.column("temp_c");
  std::array<std::size_t, 4> table{};
  std::vector<std::string_view> present, missing;
  for (std::size_t k = 0; k < kTableColumns.size(); ++k) {
    const auto i = csv.column(kTableColumns[k]);
    (i ? present : missing).push_back(kTableColumns[k]);
    if (i) table[k] = *i;
  }
  if (!present.empty() && !missing.empty()) {
    throw core::InputError(where, fmt::format("column {}: the four table columns come all or none; "
                                              "missing {}",
                                              present.front(), fmt::join(missing, ", ")));
  }
  if (missing.empty()) c.table = table;
  return c;
}

// The rules between meta.json and the header of samples.csv.
void check_meta_against_columns(const ImportMeta& meta, const Columns2& c,
                                const core::CsvReader& csv, const std::string& meta_file) {
  const std::string where = csv.file() + ":1";
  if (meta.has_table && !c.table) {
    throw core::InputError(where, fmt::format("no table columns ({}), but {} has a table: give the "
                                              "columns, or leave out table when the orientation is "
                                              "not known",
                                              fmt::join(kTableColumns, ", "), meta_file));
  }
  if (!meta.has_table && c.table) {
    throw core::InputError(where, fmt::format("column outer_deg: the table columns need {}'s "
                                              "table (the axes they turn about)",
                                              meta_file));
  }
  if (c.temp && !meta.has_temperature_unit) {
    throw core::InputError(meta_file + ": units.temperature",
                           fmt::format("required with the temp_c column of {}", csv.file()));
  }
  if (!c.temp && meta.has_temperature_unit) {
    throw core::InputError(meta_file + ": units.temperature",
                           fmt::format("given, but {} has no temp_c column", csv.file()));
  }
  if (!meta.sections.empty() && !c.step) {
    throw core::InputError(
        meta_file + ": sections",
        fmt::format("need the step column in {} (sections are keyed by step)", csv.file()));
  }
}

}  // namespace

nlohmann::json ImportSection::to_json() const {
  nlohmann::json j{{"label", label}, {"kind", kind}};
  if (kind == "static") {
    j["up"] = up;
  } else {
    j["axis"] = axis;
    j["angle_deg"] = angle_deg;
  }
  return j;
}

ImportMeta read_import_meta(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw core::InputError(file, "cannot open the file");
  ImportMeta meta;
  meta.text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  meta.doc = core::parse_json_text(meta.text, file);
  // The format decides which schema applies; anything else is checked against /1's, which
  // names the format field.
  if (meta.doc.is_object() && meta.doc.value("format", nlohmann::json()) == kImportFormat2) {
    core::validate_or_throw(core::schema("import-meta-2.schema.json"), meta.doc, file);
    meta.version = 2;
    check_meta_2(meta, file);
    return meta;
  }
  core::validate_or_throw(core::schema("import-meta.schema.json"), meta.doc, file);
  check_unit_vector(meta.doc["table"]["outer_axis"], file, "table.outer_axis");
  check_unit_vector(meta.doc["table"]["inner_axis"], file, "table.inner_axis");
  return meta;
}

// How a /2 column's values convert to the store's units (decided once, not per value).
enum class Convert { kAsIs, kScale, kCounts };

struct ImportSampleReader::Impl {
  Impl(const std::filesystem::path& path, const ImportMeta& m, std::filesystem::path mp)
      : csv(path), meta(m), meta_path(std::move(mp)) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    file_bytes = ec ? 0 : size;
  }

  core::CsvReader csv;
  const ImportMeta& meta;
  std::filesystem::path meta_path;
  std::uint64_t file_bytes = 0;
  std::optional<Columns2> columns;  // /2 only
  Convert gyro = Convert::kAsIs;
  Convert accel = Convert::kAsIs;
  std::uint64_t rows = 0;
  std::set<std::int64_t> steps;  // the step values seen, when meta.json has sections
  bool ended = false;

  void row_1(ImportRow& r) const {
    r.line = csv.line();
    r.t_s = csv.number(0);
    r.step = csv.integer(1);
    r.outer_deg = csv.number(2);
    r.inner_deg = csv.number(3);
    r.outer_rate_dps = csv.number(4);
    r.inner_rate_dps = csv.number(5);
    r.temp_c = csv.number(6);
    for (int i = 0; i < 3; ++i) {
      r.gyro_dps[i] = csv.number(7 + static_cast<std::size_t>(i));
      r.accel_mps2[i] = csv.number(10 + static_cast<std::size_t>(i));
    }
  }

  void row_2(ImportRow& r) const {
    const Columns2& c = *columns;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    constexpr double kDegPerRad = 180.0 / std::numbers::pi;
    r.line = csv.line();
    r.t_s = csv.number(c.t);
    r.step = c.step ? csv.integer(*c.step) : 0;
    if (c.table) {
      r.outer_deg = csv.number((*c.table)[0]);
      r.inner_deg = csv.number((*c.table)[1]);
      r.outer_rate_dps = csv.number((*c.table)[2]);
      r.inner_rate_dps = csv.number((*c.table)[3]);
    } else {
      r.outer_deg = r.inner_deg = r.outer_rate_dps = r.inner_rate_dps = nan;
    }
    r.temp_c = c.temp ? csv.number(*c.temp) : nan;
    for (int i = 0; i < 3; ++i) {
      const double g = csv.number(c.gyro[static_cast<std::size_t>(i)]);
      const double a = csv.number(c.accel[static_cast<std::size_t>(i)]);
      r.gyro_dps[i] = gyro == Convert::kAsIs ? g
                      : gyro == Convert::kScale
                          ? g * kDegPerRad
                          : (g - meta.gyro_offset_counts[i]) / meta.gyro_counts_per_dps[i];
      r.accel_mps2[i] = accel == Convert::kAsIs ? a
                        : accel == Convert::kScale
                            ? a * kG0
                            : (a - meta.accel_offset_counts[i]) / meta.accel_counts_per_mps2[i];
    }
  }

  // The rules about the whole file, once it has been read.
  void check_end() const {
    if (rows == 0) throw core::InputError(csv.file(), "no samples after the header");
    // Every section names a step that has samples: a typo in a key must not leave a section
    // silently unused.
    for (const auto& [step, section] : meta.sections) {
      if (!steps.contains(step)) {
        throw core::InputError(fmt::format("{}: sections[\"{}\"]", meta_path.string(), step),
                               fmt::format("no sample of {} has step {} (label '{}')", csv.file(),
                                           step, section.label));
      }
    }
  }
};

ImportSampleReader::ImportSampleReader(const std::filesystem::path& path, const ImportMeta& meta,
                                       std::filesystem::path meta_path)
    : impl_(std::make_unique<Impl>(path, meta, std::move(meta_path))) {
  core::CsvReader& csv = impl_->csv;
  if (meta.version == 1) {
    if (csv.header() != kImportCsvHeader) {
      throw core::InputError(
          csv.file() + ":1",
          fmt::format("the header must be exactly '{}', got '{}'", kImportCsvHeader, csv.header()));
    }
    return;
  }
  const Columns2 c = map_columns_2(csv);
  check_meta_against_columns(meta, c, csv, impl_->meta_path.string());
  impl_->columns = c;
  has_step_ = c.step.has_value();
  has_table_ = c.table.has_value();
  has_temperature_ = c.temp.has_value();
  const auto convert = [](const std::string& unit, const char* as_is, const char* scaled) {
    return unit == as_is ? Convert::kAsIs : unit == scaled ? Convert::kScale : Convert::kCounts;
  };
  impl_->gyro = convert(meta.gyro_unit, "deg/s", "rad/s");
  impl_->accel = convert(meta.accel_unit, "m/s^2", "g");
}

ImportSampleReader::~ImportSampleReader() = default;

const std::string& ImportSampleReader::file() const { return impl_->csv.file(); }

double ImportSampleReader::progress() const {
  if (impl_->file_bytes == 0) return 0.0;
  return std::min(
      1.0, static_cast<double>(impl_->csv.offset()) / static_cast<double>(impl_->file_bytes));
}

bool ImportSampleReader::read(std::vector<ImportRow>& batch, std::size_t max) {
  Impl& m = *impl_;
  batch.clear();
  if (m.ended) return false;
  const bool v1 = m.meta.version == 1;
  const bool track_steps = !m.meta.sections.empty();
  while (batch.size() < max && m.csv.next()) {
    ImportRow& r = batch.emplace_back();
    if (v1) {
      m.row_1(r);
    } else {
      m.row_2(r);
    }
    if (track_steps) m.steps.insert(r.step);
    ++m.rows;
  }
  if (!batch.empty()) return true;
  m.ended = true;
  m.check_end();
  return false;
}

}  // namespace calstand::store::detail

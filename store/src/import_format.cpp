#include "import_format.hpp"

#include <fmt/format.h>

#include <array>
#include <charconv>
#include <cmath>
#include <fstream>

#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"

namespace calstand::store::detail {
namespace {

constexpr std::array<std::string_view, 13> kColumns = {"t",
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

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
    s.remove_suffix(1);
  }
  return s;
}

double parse_number(std::string_view text, std::string_view column, const std::string& where) {
  std::string_view t = trim(text);
  if (t.starts_with('+')) t.remove_prefix(1);
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (t.empty() || ec != std::errc() || ptr != t.data() + t.size()) {
    throw core::InputError(where, fmt::format("column {}: '{}' is not a number", column, text));
  }
  if (!std::isfinite(v)) {
    throw core::InputError(where,
                           fmt::format("column {}: '{}' is not a finite number", column, text));
  }
  return v;
}

std::int64_t parse_step(std::string_view text, const std::string& where) {
  std::string_view t = trim(text);
  if (t.starts_with('+')) t.remove_prefix(1);
  std::int64_t v = 0;
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (t.empty() || ec != std::errc() || ptr != t.data() + t.size()) {
    throw core::InputError(where, fmt::format("column step: '{}' is not an integer", text));
  }
  return v;
}

void check_unit_vector(const nlohmann::json& v, const std::string& file, const char* field) {
  const Eigen::Vector3d a(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
  if (std::abs(a.norm() - 1.0) > 1e-6) {
    throw core::InputError(fmt::format("{}: {}", file, field),
                           fmt::format("must be a unit vector (norm is {:.6g})", a.norm()));
  }
}

}  // namespace

ImportMeta read_import_meta(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw core::InputError(file, "cannot open the file");
  ImportMeta meta;
  meta.text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  meta.doc = core::parse_json_text(meta.text, file);
  core::validate_or_throw(core::schema("import-meta.schema.json"), meta.doc, file);
  check_unit_vector(meta.doc["table"]["outer_axis"], file, "table.outer_axis");
  check_unit_vector(meta.doc["table"]["inner_axis"], file, "table.inner_axis");
  return meta;
}

std::vector<ImportRow> read_import_samples(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw core::InputError(file, "cannot open the file");
  std::string line;
  std::size_t number = 0;
  if (!std::getline(in, line)) throw core::InputError(file, "empty file: no header");
  ++number;
  std::string_view header = trim(line);
  if (header.starts_with("\xEF\xBB\xBF")) header.remove_prefix(3);  // UTF-8 byte order mark
  if (header != kImportCsvHeader) {
    throw core::InputError(file + ":1", fmt::format("the header must be exactly '{}', got '{}'",
                                                    kImportCsvHeader, header));
  }
  std::vector<ImportRow> rows;
  std::size_t blank_line = 0;  // a blank line is only allowed at the end
  std::array<std::string_view, kColumns.size()> fields;
  while (std::getline(in, line)) {
    ++number;
    const std::string where = fmt::format("{}:{}", file, number);
    if (trim(line).empty()) {
      if (blank_line == 0) blank_line = number;
      continue;
    }
    if (blank_line != 0) {
      throw core::InputError(fmt::format("{}:{}", file, blank_line), "empty line before more data");
    }
    std::size_t n = 0;
    std::string_view rest = line;
    for (;;) {
      const std::size_t comma = rest.find(',');
      if (n < fields.size()) fields[n] = rest.substr(0, comma);
      ++n;
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
    if (n != fields.size()) {
      throw core::InputError(where, fmt::format("expected {} columns, got {}", fields.size(), n));
    }
    ImportRow r;
    r.line = number;
    r.t_s = parse_number(fields[0], kColumns[0], where);
    r.step = parse_step(fields[1], where);
    r.outer_deg = parse_number(fields[2], kColumns[2], where);
    r.inner_deg = parse_number(fields[3], kColumns[3], where);
    r.outer_rate_dps = parse_number(fields[4], kColumns[4], where);
    r.inner_rate_dps = parse_number(fields[5], kColumns[5], where);
    r.temp_c = parse_number(fields[6], kColumns[6], where);
    for (int i = 0; i < 3; ++i) {
      r.gyro_dps[i] = parse_number(fields[7 + i], kColumns[7 + i], where);
      r.accel_mps2[i] = parse_number(fields[10 + i], kColumns[10 + i], where);
    }
    rows.push_back(r);
  }
  if (rows.empty()) throw core::InputError(file, "no samples after the header");
  return rows;
}

}  // namespace calstand::store::detail

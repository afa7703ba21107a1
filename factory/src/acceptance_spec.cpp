#include "factory/acceptance_spec.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <system_error>

#include "analysis/run_model.hpp"
#include "core/error_terms.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"
#include "core/suggest.hpp"
#include "factory/acceptance_names.hpp"
#include "store/hash.hpp"

namespace calstand::analysis {
namespace {

std::optional<double> number_at(const nlohmann::json& j, const char* key) {
  if (!j.contains(key)) return std::nullopt;
  return j[key].get<double>();
}

std::string quoted(const std::string& text) { return "\"" + text + "\""; }

// A pattern that names nothing: the term it most likely meant, e.g. ` (did you mean
// gyro_bias.*?)` for `gyro_bais.*`.
std::string suggestion(const std::string& pattern, const std::vector<NamedQuantity>& names) {
  const auto dot = pattern.find('.');
  const std::string head = pattern.substr(0, dot);
  if (head.find('*') != std::string::npos) return "";
  std::vector<std::string> heads;
  for (const auto& n : names) {
    std::string h = n.name.substr(0, n.name.find('.'));
    if (heads.empty() || heads.back() != h) heads.push_back(std::move(h));
  }
  const std::vector<std::string_view> views(heads.begin(), heads.end());
  const std::string best = core::closest_name(head, views);
  if (best.empty()) return "";
  return " (did you mean " + best + (dot == std::string::npos ? "" : pattern.substr(dot)) + "?)";
}

// The names a pattern limits, and their one unit. What a schema cannot say: a limit's unit must
// be the unit of every name its pattern matches, so a limit is never read in another unit (a
// gyro bias limit in deg/h would otherwise be 3600 times too loose).
void check_pattern(const AcceptanceLimit& limit, const std::vector<NamedQuantity>& names,
                   const char* what, std::vector<core::SchemaViolation>& out) {
  std::map<std::string, std::vector<std::string>> by_unit;  // unit -> terms (names up to '.')
  for (const auto& n : names) {
    if (!glob_match(limit.pattern, n.name)) continue;
    auto& terms = by_unit[n.unit];
    const std::string term = n.name.substr(0, n.name.find('.'));
    if (terms.empty() || terms.back() != term) terms.push_back(term);
  }
  const std::string key = std::string(to_string(limit.kind));
  if (by_unit.empty()) {
    out.push_back({limit.where + "." + key, fmt::format("{} matches no {}{}", quoted(limit.pattern),
                                                        what, suggestion(limit.pattern, names))});
    return;
  }
  if (by_unit.size() > 1) {
    std::string list;
    for (const auto& [unit, terms] : by_unit) {
      for (const auto& t : terms) list += (list.empty() ? "" : ", ") + t + " in " + unit;
    }
    out.push_back({limit.where + "." + key,
                   fmt::format("{} matches {}s of different units ({}): one limit per unit",
                               quoted(limit.pattern), what, list)});
    return;
  }
  const std::string& unit = by_unit.begin()->first;
  if (limit.unit != unit) {
    std::string terms;
    for (const auto& t : by_unit.begin()->second) terms += (terms.empty() ? "" : ", ") + t;
    out.push_back({limit.where + ".unit",
                   fmt::format("{} is not the unit of {} ({} {} in {}): the limit is refused",
                               quoted(limit.unit), limit.pattern, terms,
                               by_unit.begin()->second.size() == 1 ? "is" : "are", unit)});
  }
}

void check_fit_unit(const AcceptanceLimit& limit, bool unit_given,
                    std::vector<core::SchemaViolation>& out) {
  for (const auto& f : fit_quantities()) {
    if (f.name != limit.pattern) continue;
    if (unit_given && limit.unit != f.unit) {
      out.push_back({limit.where + ".unit",
                     f.unit.empty() ? fmt::format("{} has no unit; leave out \"unit\"", f.name)
                                    : fmt::format("{} is not the unit of {} ({})",
                                                  quoted(limit.unit), f.name, f.unit)});
    }
  }
}

void check_bounds(const AcceptanceLimit& limit, std::vector<core::SchemaViolation>& out) {
  // Either |v| <= max_abs or a zone [min, max]: both at once would be two zones in one limit,
  // whose intersection a reader has to work out.
  if (limit.value.max_abs && (limit.value.min || limit.value.max)) {
    out.push_back(
        {limit.where,
         "max_abs with min or max: give either max_abs or min/max (two limits for both)"});
  }
  if (limit.value.min && limit.value.max && *limit.value.min > *limit.value.max) {
    out.push_back(
        {limit.where, fmt::format("min {} is above max {}", *limit.value.min, *limit.value.max)});
  }
}

AcceptanceLimit read_limit(const nlohmann::json& j, const std::string& where,
                           std::vector<core::SchemaViolation>& out) {
  AcceptanceLimit limit;
  limit.where = where;
  limit.unit = j.value("unit", "");
  limit.value = {number_at(j, "max_abs"), number_at(j, "min"), number_at(j, "max")};
  limit.max_sigma = number_at(j, "max_sigma");
  if (j.contains("parameter")) {
    limit.kind = LimitKind::kParameter;
    limit.pattern = j["parameter"].get<std::string>();
    check_pattern(limit, catalogue_parameters(), "parameter of the error-model catalogue", out);
  } else if (j.contains("noise")) {
    limit.kind = LimitKind::kNoise;
    limit.pattern = j["noise"].get<std::string>();
    check_pattern(limit, noise_quantities(), "noise figure", out);
  } else if (j.contains("fit")) {
    limit.kind = LimitKind::kFit;
    limit.pattern = j["fit"].get<std::string>();
    check_fit_unit(limit, j.contains("unit"), out);
    if (!j.contains("unit")) {
      for (const auto& f : fit_quantities()) {
        if (f.name == limit.pattern) limit.unit = f.unit;
      }
    }
  } else {
    limit.kind = LimitKind::kTemperatureRange;
    limit.temperature_min_c = j["temperature_range_c"][0].get<double>();
    limit.temperature_max_c = j["temperature_range_c"][1].get<double>();
    limit.unit = "degC";
    if (limit.temperature_min_c > limit.temperature_max_c) {
      out.push_back({where + ".temperature_range_c",
                     fmt::format("[{}, {}] is not [min, max]", limit.temperature_min_c,
                                 limit.temperature_max_c)});
    }
  }
  check_bounds(limit, out);
  return limit;
}

}  // namespace

std::string_view to_string(LimitKind kind) {
  switch (kind) {
    case LimitKind::kParameter:
      return "parameter";
    case LimitKind::kNoise:
      return "noise";
    case LimitKind::kFit:
      return "fit";
    case LimitKind::kTemperatureRange:
      return "temperature_range_c";
  }
  return "parameter";
}

AcceptanceSpec parse_acceptance_spec(std::string_view text, const std::string& file_name) {
  const nlohmann::json doc = core::parse_json_text(text, file_name);
  core::validate_or_throw(core::schema("acceptance.schema.json"), doc, file_name);
  AcceptanceSpec spec;
  spec.file = file_name;
  spec.name = doc["name"].get<std::string>();
  spec.sha256 = store::sha256_hex(text);
  spec.k = doc.value("k", kDefaultCoverageFactor);
  std::vector<core::SchemaViolation> violations;
  for (std::size_t i = 0; i < doc["limits"].size(); ++i) {
    spec.limits.push_back(read_limit(doc["limits"][i], fmt::format("limits[{}]", i), violations));
  }
  if (doc.contains("validation")) {
    const nlohmann::json& v = doc["validation"];
    ValidationSpec validation;
    for (const auto& term : v.value("model", nlohmann::json::array())) {
      validation.model.push_back(term.get<std::string>());
    }
    if (!validation.model.empty()) {
      try {
        model_from_lists(validation.model, {});
      } catch (const core::InputError& e) {
        // model_from_lists() names the entry ("model[1]") in where() and says why after it.
        const std::string what = e.what();
        violations.push_back(
            {"validation." + e.where(), what.substr(std::min(what.size(), e.where().size() + 2))});
      }
    }
    for (std::size_t i = 0; i < v["limits"].size(); ++i) {
      validation.limits.push_back(
          read_limit(v["limits"][i], fmt::format("validation.limits[{}]", i), violations));
    }
    spec.validation = std::move(validation);
  }
  if (!violations.empty()) throw core::SchemaError(file_name, std::move(violations));
  return spec;
}

AcceptanceSpec read_acceptance_spec(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw core::InputError(path, "is a directory, not a specification file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int err = errno;
    throw core::InputError(path, "cannot open: " + std::generic_category().message(err));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw core::InputError(path, "cannot read the file");
  return parse_acceptance_spec(text.str(), path);
}

nlohmann::json spec_json(const AcceptanceSpec& spec) {
  return {{"name", spec.name}, {"file", spec.file}, {"sha256", spec.sha256}, {"k", spec.k}};
}

}  // namespace calstand::analysis

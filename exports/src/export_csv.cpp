// One CSV row per parameter, for spreadsheets and MES import (docs/exports.md, "CSV"): the
// record's numbers as they are, in the contract's names and units, each row carrying the
// unit's identity so that rows of many units can be concatenated.
#include <fmt/format.h>

#include <string>
#include <vector>

#include "export_formats.hpp"
#include "export_terms.hpp"

namespace calstand::analysis::exporting {
namespace {

// RFC 4180: a field holding a comma, a quote or a line break is quoted, quotes doubled.
std::string field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

// Round-trip precision: a spreadsheet's number is the record's number.
std::string number(double v) { return fmt::format("{:.17g}", v); }

std::string row(const std::vector<std::string>& fields) {
  std::string line;
  for (const std::string& f : fields) line += (line.empty() ? "" : ",") + field(f);
  return line + "\r\n";
}

}  // namespace

ExportResult export_csv(const solver::Calibration& calibration) {
  const nlohmann::json& r = calibration.record;
  const nlohmann::json device = r.value("device", nlohmann::json::object());
  std::string runs;
  for (const auto& run : r.value("runs", nlohmann::json::array())) {
    runs += (runs.empty() ? "" : ";") + run.dump();
  }
  const nlohmann::json procedure = r.value("procedure", nlohmann::json::object());
  const nlohmann::json tref = r.value("temperature_ref_c", nlohmann::json());
  const std::vector<std::string> identity = {device.value("name", ""),
                                             device.value("model", ""),
                                             device.value("serial", ""),
                                             r.value("station", ""),
                                             runs,
                                             procedure.value("name", ""),
                                             procedure.value("sha256", ""),
                                             r.value("created_utc", ""),
                                             tref.is_number() ? number(tref.get<double>()) : ""};

  ExportResult out;
  out.text = row({"device", "device_model", "serial", "station", "runs", "procedure",
                  "procedure_sha256", "created_utc", "temperature_ref_c", "parameter", "value",
                  "sigma", "unit", "status", "note"});
  const auto add = [&](std::vector<std::string> rest) {
    std::vector<std::string> fields = identity;
    fields.insert(fields.end(), rest.begin(), rest.end());
    out.text += row(fields);
  };
  for (const auto& p : r.value("parameters", nlohmann::json::array())) {
    add({p.value("name", ""), number(p.value("value", 0.0)), number(p.value("sigma", 0.0)),
         p.value("unit", ""), "fitted", ""});
  }
  // The parameters the runs did not determine have no value: a row each says so, rather than
  // a number a spreadsheet would sum.
  for (const auto& u : r.value("unidentifiable", nlohmann::json::array())) {
    const std::string name = u.value("name", "");
    std::string unit;
    for (const auto& p : calibration.model.parameters()) {
      if (p.name == name) unit = p.unit;
    }
    add({name, "", "", unit, "not determined", u.value("reason", "")});
  }
  return out;
}

}  // namespace calstand::analysis::exporting

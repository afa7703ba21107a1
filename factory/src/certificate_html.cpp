#include <fmt/format.h>

#include "core/version.hpp"
#include "factory/certificate.hpp"
#include "render/markup_escape.hpp"

namespace calstand::analysis {
namespace {

// A4 portrait with 12 mm margins: small type so that a full model's parameters, the checks and
// the plot fit one page, as a certificate per unit must.
constexpr const char* kCertificateCss = R"(
@page { size: A4 portrait; margin: 12mm; }
* { box-sizing: border-box; }
body { margin: 0; color: #1d2733; font: 9pt/1.3 "Helvetica Neue", Helvetica, Arial, sans-serif; }
.page { width: 186mm; margin: 0 auto; }
header { display: flex; justify-content: space-between; align-items: flex-end;
         border-bottom: 2px solid #1d2733; padding-bottom: 4px; margin-bottom: 6px; }
header h1 { font-size: 16pt; margin: 0; }
header .number { font-size: 10pt; text-align: right; }
h2 { font-size: 10pt; margin: 7px 0 3px; border-bottom: 1px solid #dde3ea; }
.cols { display: grid; grid-template-columns: minmax(0, 1fr) minmax(0, 1fr); gap: 0 8mm; }
table { border-collapse: collapse; width: 100%; }
th, td { text-align: left; padding: 1px 4px; border-bottom: 1px solid #eef1f4; vertical-align: top;
         overflow-wrap: break-word; }
th { background: #f0f3f7; font-weight: 600; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
table.kv th { width: 34%; background: none; font-weight: 600; }
.verdict { display: inline-block; padding: 0 6px; border-radius: 6px; font-weight: 700;
           line-height: 1.25; }
table.checks { font-size: 7.5pt; }
p.rule { font-size: 7.5pt; color: #6b7785; margin: 2px 0; }
.pass { background: #d8f0dc; color: #1e7b34; }
.fail { background: #fbe0dd; color: #b3261e; }
.indeterminate, .overdue { background: #fff1d6; color: #a86400; }
.dim { color: #6b7785; }
code { font-size: 7.5pt; overflow-wrap: anywhere; }
svg { display: block; width: 100%; height: auto; }
footer { margin-top: 6px; border-top: 1px solid #dde3ea; padding-top: 3px; font-size: 7.5pt;
         color: #6b7785; }
)";

std::string esc(const std::string& text) { return html_escape(text); }

std::string number(const nlohmann::json& v) {
  return v.is_number() ? fmt::format("{:.5g}", v.get<double>()) : std::string("-");
}

std::string text_of(const nlohmann::json& j, const char* key) {
  if (!j.contains(key)) return "-";
  const nlohmann::json& v = j[key];
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number()) return number(v);
  if (v.is_null()) return "-";
  return v.dump();
}

std::string verdict_badge(const std::string& verdict) {
  return fmt::format("<span class=\"verdict {0}\">{0}</span>", esc(verdict));
}

std::string identity_section(const CertificateData& d) {
  const nlohmann::json& site = d.site;
  std::string s = "<div class=\"cols\"><div><h2>Unit</h2><table class=\"kv\">";
  s += fmt::format("<tr><th>Model</th><td>{}</td></tr>", esc(d.model.empty() ? "-" : d.model));
  s += fmt::format("<tr><th>Serial number</th><td><b>{}</b></td></tr>",
                   esc(d.serial.empty() ? "(none recorded)" : d.serial));
  s += fmt::format("<tr><th>Slot on the station</th><td>{}</td></tr>", esc(d.device));
  s += "</table><h2>Procedure</h2><table class=\"kv\">";
  s += fmt::format("<tr><th>Procedure</th><td>{} (run {})</td></tr>", esc(d.procedure), d.run);
  s += fmt::format("<tr><th>SHA-256</th><td><code>{}</code></td></tr>", esc(d.procedure_sha256));
  s += fmt::format("<tr><th>Measured</th><td>{} to {}</td></tr>", esc(d.run_started_utc),
                   esc(d.run_ended_utc));
  std::string terms;
  for (const auto& t : d.record.value("model", nlohmann::json::array())) {
    terms += (terms.empty() ? "" : ", ") + (t.is_string() ? t.get<std::string>() : t.dump());
  }
  s += fmt::format("<tr><th>Model fitted</th><td>{}</td></tr>", esc(terms));
  s += "</table></div><div><h2>Station and conditions</h2><table class=\"kv\">";
  s += fmt::format("<tr><th>Station</th><td>{}</td></tr>", esc(d.station));
  s += fmt::format("<tr><th>Site</th><td>{} deg N, {} deg E, {} m</td></tr>",
                   text_of(site, "latitude_deg"), text_of(site, "longitude_deg"),
                   text_of(site, "height_m"));
  const nlohmann::json range = d.record.value("valid_temperature_c", nlohmann::json::object());
  s += fmt::format("<tr><th>Temperature</th><td>{} to {} degC (T<sub>ref</sub> {} degC)</td></tr>",
                   text_of(range, "min"), text_of(range, "max"),
                   text_of(d.record, "temperature_ref_c"));
  s += "</table><h2>Station equipment</h2>";
  if (d.equipment.empty()) {
    s += "<p class=\"dim\">The station file states no equipment calibration status.</p>";
  } else {
    s += "<table><tr><th>Equipment</th><th>Id</th><th>Calibrated</th><th>Due</th></tr>";
    for (const EquipmentStatus& e : d.equipment) {
      s += fmt::format(
          "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}{}</td></tr>", esc(e.name),
          esc(e.id.empty() ? "-" : e.id), esc(e.calibrated.empty() ? "-" : e.calibrated),
          esc(e.due),
          e.overdue ? " <span class=\"verdict overdue\">overdue at the run</span>" : "");
    }
    s += "</table>";
  }
  return s + "</div></div>";
}

std::string parameter_section(const CertificateData& d) {
  const auto& parameters = d.record.value("parameters", nlohmann::json::array());
  std::string rows;
  for (const auto& p : parameters) {
    const double sigma = p.value("sigma", 0.0);
    rows += fmt::format(
        "<tr><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{:.3g}</td>"
        "<td>{}</td></tr>",
        esc(p.value("name", "")), number(p["value"]), kCertificateCoverageFactor * sigma,
        esc(p.value("unit", "")));
  }
  // Two columns of the table when long: a full model has some thirty parameters.
  std::string s =
      fmt::format("<h2>Results (expanded uncertainty U = {:g} &sigma;, about 95 %)</h2>",
                  kCertificateCoverageFactor);
  const std::string head = "<tr><th>Parameter</th><th>Value</th><th>U</th><th>Unit</th></tr>";
  if (parameters.size() <= 14) {
    s += "<table>" + head + rows + "</table>";
  } else {
    std::string left;
    std::string right;
    std::size_t i = 0;
    const std::size_t half = (parameters.size() + 1) / 2;
    for (const auto& p : parameters) {
      const std::string row = fmt::format(
          "<tr><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{:.3g}</td>"
          "<td>{}</td></tr>",
          esc(p.value("name", "")), number(p["value"]),
          kCertificateCoverageFactor * p.value("sigma", 0.0), esc(p.value("unit", "")));
      (i++ < half ? left : right) += row;
    }
    s += "<div class=\"cols\"><table>" + head + left + "</table><table>" + head + right +
         "</table></div>";
  }
  const auto& undetermined = d.record.value("unidentifiable", nlohmann::json::array());
  if (!undetermined.empty()) {
    std::string names;
    for (const auto& u : undetermined) names += (names.empty() ? "" : ", ") + u.value("name", "");
    s += fmt::format("<p class=\"dim\">Not determined by this procedure (not applied): {}</p>",
                     esc(names));
  }
  const nlohmann::json fit = d.record.value("fit", nlohmann::json::object());
  s += fmt::format(
      "<p>Fit: chi<sup>2</sup>/dof {} over {} degrees of freedom against the run's own "
      "noise model.</p>",
      text_of(fit, "chi2_dof"), text_of(fit, "dof"));
  return s;
}

std::string acceptance_section(const CertificateData& d) {
  std::string s = "<h2>Conformity</h2>";
  if (!d.acceptance) {
    return s + "<p>Not judged against a specification (<code>calstand accept</code>).</p>";
  }
  const nlohmann::json& r = d.acceptance->result;
  s += fmt::format("<p>Specification <b>{}</b> (<code>{}</code>): {}</p>",
                   esc(d.acceptance->spec_name), esc(d.acceptance->spec_sha256.substr(0, 16)),
                   verdict_badge(d.acceptance->verdict));
  if (r.contains("decision_rule") && r["decision_rule"].is_string()) {
    s += "<p class=\"rule\">" + esc(r["decision_rule"].get<std::string>()) + "</p>";
  }
  std::vector<std::string> rows;
  for (const auto& c : r.value("checks", nlohmann::json::array())) {
    rows.push_back(fmt::format(
        "<tr><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td>"
        "<td class=\"num\">{}</td><td>{}</td><td>{}</td></tr>",
        esc(text_of(c, "check")), esc(text_of(c, "value")),
        c.contains("sigma") && c["sigma"].is_number()
            ? fmt::format("{:.2g}", c["sigma"].get<double>())
            : std::string("-"),
        esc(text_of(c, "limit")), esc(c.value("unit", "")), verdict_badge(c.value("verdict", ""))));
  }
  const std::string head =
      "<tr><th>Check</th><th>Value</th><th>&sigma;</th><th>Limit</th><th>Unit</th><th>Verdict</th>"
      "</tr>";
  // Two columns of checks when there are many: a whole specification stays on the page.
  if (rows.size() <= 6) {
    std::string table = "<table class=\"checks\">" + head;
    for (const auto& row : rows) table += row;
    return s + table + "</table>";
  }
  std::string left = "<table class=\"checks\">" + head;
  std::string right = "<table class=\"checks\">" + head;
  for (std::size_t i = 0; i < rows.size(); ++i)
    (i < (rows.size() + 1) / 2 ? left : right) += rows[i];
  return s + "<div class=\"cols\">" + left + "</table>" + right + "</table></div>";
}

}  // namespace

std::string certificate_html(const CertificateData& d) {
  std::string body = fmt::format(
      "<header><h1>Calibration certificate</h1><div class=\"number\">No. <b>{}</b><br>issued {}"
      "</div></header>",
      esc(d.number), esc(d.issued_utc));
  body += identity_section(d);
  body += parameter_section(d);
  body += acceptance_section(d);
  if (d.residuals) {
    body += "<h2>Residuals after calibration</h2>" + certificate_residual_plot(*d.residuals);
  }
  body += fmt::format(
      "<footer>calstand {} &middot; calibration record {} of run {} &middot; the parameters follow "
      "the calstand error model (error-model.md); a parameter's expanded uncertainty is {:g} times "
      "its standard uncertainty from the fit.</footer>",
      CALSTAND_VERSION, d.calibration, d.run, kCertificateCoverageFactor);
  return fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>Calibration certificate {}</title>\n<style>{}</style>\n</head>\n<body>\n"
      "<div class=\"page\">{}</div>\n</body>\n</html>\n",
      esc(d.number), kCertificateCss, body);
}

}  // namespace calstand::analysis

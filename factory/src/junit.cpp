#include "factory/junit.hpp"

#include <fmt/format.h>

#include "render/markup_escape.hpp"

namespace calstand::analysis {
namespace {

std::string attr(std::string_view text) { return html_escape(text); }

std::string number_or_none(const std::optional<double>& v) {
  return v ? fmt::format("{:.6g}", *v) : std::string("none");
}

// One line a person reads in the CI's test view: what was measured against what.
std::string check_line(const AcceptanceCheck& c) {
  return fmt::format("value {}, sigma {}, limit {}, verdict {}: {}", number_or_none(c.value),
                     number_or_none(c.sigma), describe(c.limit, c.unit), to_string(c.verdict),
                     c.reason);
}

void property(std::string& xml, const char* name, const std::string& value) {
  xml += fmt::format("      <property name=\"{}\" value=\"{}\"/>\n", name, attr(value));
}

}  // namespace

std::string junit_xml(const AcceptanceOutcome& o) {
  std::size_t tests = 0, failures = 0;
  for (const auto& u : o.units) {
    tests += u.checks.size();
    for (const auto& c : u.checks) failures += c.verdict != Verdict::kPass ? 1 : 0;
  }
  std::string xml = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  xml += fmt::format("<testsuites name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"0\">\n",
                     attr(fmt::format("calstand accept run {} against {}", o.run, o.spec.name)),
                     tests, failures);
  for (std::size_t i = 0; i < o.units.size(); ++i) {
    const UnitAcceptance& u = o.units[i];
    std::size_t unit_failures = 0;
    for (const auto& c : u.checks) unit_failures += c.verdict != Verdict::kPass ? 1 : 0;
    const std::string suite = u.serial.empty() ? u.device : u.device + " " + u.serial;
    xml += fmt::format(
        "  <testsuite name=\"{}\" id=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"0\" "
        "skipped=\"0\">\n",
        attr(suite), i, u.checks.size(), unit_failures);
    xml += "    <properties>\n";
    property(xml, "device", u.device);
    property(xml, "serial", u.serial);
    property(xml, "calibration", std::to_string(u.calibration));
    property(xml, "run", std::to_string(u.run));
    property(xml, "verdict", std::string(to_string(u.verdict)));
    property(xml, "spec", o.spec.name);
    property(xml, "spec_sha256", o.spec.sha256);
    property(xml, "k", fmt::format("{}", o.spec.k));
    property(xml, "decision_rule", decision_rule_text(o.spec.k));
    xml += "    </properties>\n";
    const std::string classname = "calstand.accept." + u.device;
    for (const auto& c : u.checks) {
      xml += fmt::format("    <testcase name=\"{}\" classname=\"{}\">\n", attr(c.check),
                         attr(classname));
      const std::string line = check_line(c);
      if (c.verdict != Verdict::kPass) {
        xml += fmt::format("      <failure type=\"{}\" message=\"{}\">{}</failure>\n",
                           to_string(c.verdict), attr(line), html_escape(line));
      }
      xml += fmt::format("      <system-out>{}</system-out>\n", html_escape(line));
      xml += "    </testcase>\n";
    }
    xml += "  </testsuite>\n";
  }
  xml += "</testsuites>\n";
  return xml;
}

}  // namespace calstand::analysis

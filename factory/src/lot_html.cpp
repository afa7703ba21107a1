#include <fmt/format.h>

#include <cmath>

#include "factory/lot.hpp"
#include "render/gnuplot_svg.hpp"
#include "render/markup_escape.hpp"
#include "render/report_style.hpp"

namespace calstand::analysis {
namespace {

std::string num(double v) { return fmt::format("{:.5g}", v); }

// Individuals chart of one parameter: each unit's value in calibration order, the centre line
// and the 3-sigma control limits; flagged outliers drawn red.
std::string control_chart(const LotParameter& p, std::size_t index) {
  std::vector<std::string> rows;
  std::vector<std::string> flagged;
  for (std::size_t i = 0; i < p.values.size(); ++i) {
    const std::string row =
        fmt::format("{} {} {}", i + 1, gp_number(p.values[i]), data_text(p.serials[i]));
    rows.push_back(row);
    for (const LotOutlier& o : p.outliers) {
      if (o.serial == p.serials[i]) flagged.push_back(row);
    }
  }
  if (flagged.empty()) flagged.push_back("NaN NaN \"\"");
  std::string s = svg_terminal(900, 230) + data_block("v", rows) + data_block("o", flagged);
  s += fmt::format("set xrange [0.5:{}]\nset xlabel 'unit, in calibration order'\n",
                   static_cast<double>(p.values.size()) + 0.5);
  s += fmt::format("set ylabel {}\nset key outside right top\n",
                   gnuplot_quote(p.name + " [" + p.unit + "]"));
  s += horizontal_line(p.mean, "#2ca02c", 1);
  if (p.control_upper > p.control_lower) {
    s += horizontal_line(p.control_upper, "#d62728", 2) +
         horizontal_line(p.control_lower, "#d62728", 2);
  }
  s += "plot $v using 1:2 with linespoints pt 7 ps 0.7 lc rgb '#1f77b4' title 'unit', "
       "$o using 1:2 with points pt 6 ps 1.8 lw 2 lc rgb '#d62728' title 'outlier', "
       "keyentry with lines dt 2 lc rgb '#d62728' title 'control limits'\n";
  return gnuplot_svg(s, fmt::format("lot-{}", index), p.name + " across the lot");
}

}  // namespace

std::string lot_html(const LotStatistics& lot) {
  std::string body = fmt::format(
      "<header><h1>Lot statistics</h1><p>{} units{}{}</p></header>", lot.units.size(),
      lot.since_utc.empty() ? "" : ", calibrated since " + html_escape(lot.since_utc),
      lot.records_without_serial == 0
          ? ""
          : fmt::format(" ({} records without a serial left out)", lot.records_without_serial));
  body += "<section><h2>Yield</h2>";
  body += fmt::format(
      "<p>{} passed, {} failed, {} indeterminate, {} not judged: yield {}.</p>", lot.passed,
      lot.failed, lot.indeterminate, lot.not_judged,
      lot.yield ? fmt::format("{:.1f} %", 100.0 * *lot.yield) : std::string("- (none judged)"));
  body += "</section><section><h2>Parameters across the lot</h2>";
  body += fmt::format(
      "<p class=\"lead\">A unit more than {:g} robust sigmas (1.4826 MAD) from the lot's median is "
      "flagged, even when it passes: it is unlike its siblings.</p>",
      kLotOutlierZ);
  body +=
      "<table><tr><th>parameter</th><th>unit</th><th>n</th><th>mean</th><th>std</th>"
      "<th>median</th><th>min</th><th>max</th><th>outliers</th></tr>";
  for (const LotParameter& p : lot.parameters) {
    std::string flagged;
    for (const LotOutlier& o : p.outliers) {
      flagged += fmt::format("{}{} (z {}{})", flagged.empty() ? "" : ", ", html_escape(o.serial),
                             std::isfinite(o.robust_z) ? fmt::format("{:.1f}", o.robust_z) : "inf",
                             o.verdict.empty() ? "" : ", " + html_escape(o.verdict));
    }
    body += fmt::format(
        "<tr><td>{}</td><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td>"
        "<td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td>"
        "<td class=\"num\">{}</td><td class=\"{}\">{}</td></tr>",
        html_escape(p.name), html_escape(p.unit), p.values.size(), num(p.mean), num(p.std_dev),
        num(p.median), num(p.min), num(p.max), flagged.empty() ? "" : "bad",
        flagged.empty() ? "-" : flagged);
  }
  body += "</table></section><section><h2>Control charts</h2>";
  body +=
      "<p class=\"lead\">Individuals charts: the lot mean and the 3-sigma limits from the "
      "mean moving range between consecutive units.</p>";
  for (std::size_t i = 0; i < lot.parameters.size(); ++i) {
    body += control_chart(lot.parameters[i], i);
  }
  body += "</section>";
  return fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>calstand lot statistics</title>\n<style>{}</style>\n</head>\n<body>\n<main>\n{}"
      "<footer>calstand lot</footer>\n</main>\n</body>\n</html>\n",
      report_css(), body);
}

}  // namespace calstand::analysis

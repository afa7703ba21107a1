// The style sheet of calstand's HTML reports.
#include "render/report_style.hpp"

#include <fmt/format.h>

#include "render/markup_escape.hpp"

namespace calstand::analysis {
namespace {

constexpr const char* kStyle = R"(
:root { --ink: #1d2733; --dim: #6b7785; --line: #dde3ea; --good: #1e7b34; --warn: #a86400;
        --bad: #b3261e; --accent: #1f77b4; }
* { box-sizing: border-box; }
body { margin: 0; background: #f3f5f8; color: var(--ink);
       font: 15px/1.45 "Helvetica Neue", Helvetica, Arial, sans-serif; }
main { max-width: 1120px; margin: 0 auto; padding: 24px 20px 48px; }
header { background: #1d2733; color: #fff; padding: 22px 28px; border-radius: 10px; }
header h1 { margin: 0 0 6px; font-size: 24px; font-weight: 600; }
header p { margin: 4px 0; color: #c9d3de; }
header code { color: #fff; overflow-wrap: anywhere; }
.badge { display: inline-block; padding: 2px 10px; border-radius: 12px; font-weight: 600;
         font-size: 13px; margin-left: 8px; }
.badge.good { background: #d8f0dc; color: var(--good); }
.badge.bad { background: #fbe0dd; color: var(--bad); }
.badge.neutral { background: #e3ecf5; color: #1f4e79; }
section { background: #fff; border: 1px solid var(--line); border-radius: 10px;
          padding: 18px 24px 22px; margin-top: 20px; }
section h2 { margin: 0 0 4px; font-size: 19px; }
section h3 { margin: 18px 0 6px; font-size: 15px; }
p.lead { margin: 0 0 12px; color: var(--dim); }
svg { display: block; width: 100%; height: auto; margin: 8px 0 12px; }
.narrow svg { max-width: 760px; margin-left: auto; margin-right: auto; }
.grid { display: grid; grid-template-columns: repeat(auto-fit, minmax(320px, 1fr)); gap: 14px; }
table { border-collapse: collapse; width: 100%; margin: 8px 0; font-size: 13.5px; }
th, td { text-align: left; padding: 5px 9px; border-bottom: 1px solid var(--line);
         vertical-align: top; }
th { background: #f0f3f7; font-weight: 600; }
tbody tr:nth-child(even) { background: #fafbfc; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.good { color: var(--good); font-weight: 600; }
td.warn { color: var(--warn); font-weight: 600; }
td.bad { color: var(--bad); font-weight: 600; }
td.model { font-family: monospace; font-size: 12px; word-break: break-all; }
.dim { color: var(--dim); }
.advice { border-left: 4px solid var(--accent); background: #eef5fb; padding: 10px 14px;
          margin: 10px 0; }
.advice.good { border-color: var(--good); background: #eef8f0; }
.advice.bad { border-color: var(--bad); background: #fdf0ee; }
footer { color: var(--dim); font-size: 12px; margin-top: 18px; text-align: center; }
)";

}  // namespace

const char* report_css() { return kStyle; }

std::string advice_section_start(bool explained, const std::string& advice) {
  return fmt::format(
      "<section id=\"candidates\"><h2>Which effect is missing</h2>\n"
      "<div class=\"advice {}\"><b>{}</b> {}</div>\n",
      explained ? "good" : "bad", explained ? "Explained." : "Not explained.", html_escape(advice));
}

std::string report_page(std::int64_t run, const std::string& procedure, const std::string& body,
                        const std::string& stamp) {
  return fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      "<title>calstand report: run {0} ({1})</title>\n<style>{2}</style>\n</head>\n<body>\n<main>\n"
      "{3}<footer>calstand report &middot; run {0} &middot; {4}</footer>\n"
      "</main>\n</body>\n</html>\n",
      run, html_escape(procedure), kStyle, body, html_escape(stamp));
}

}  // namespace calstand::analysis

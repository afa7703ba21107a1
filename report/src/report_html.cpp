#include "report/report_html.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <typeinfo>
#include <utility>

#include "analysis/noise_run.hpp"
#include "core/error.hpp"
#include "noise/run_noise.hpp"
#include "render/gnuplot_svg.hpp"
#include "render/report_style.hpp"
#include "report/report_datasheet.hpp"
#include "report/report_plots.hpp"
#include "report/report_tables.hpp"
#include "report/table_free_report.hpp"

namespace calstand::analysis {
namespace {

// The strongest signals, at most `count`, one per base signal and channel (r with x, x^2 and
// abs(x) of one signal tell the same story).
std::vector<solver::SignalCorrelation> top_signals(const ReportData& r, std::size_t count) {
  std::vector<solver::SignalCorrelation> out;
  std::vector<std::string> seen;
  for (const auto& s : r.diagnosis.signals) {
    std::string base = s.signal;
    if (base.starts_with("abs(")) base = base.substr(4, base.size() - 5);
    if (base.ends_with("^2")) base.resize(base.size() - 2);
    const std::string key = base + "/" + s.channel;
    if (std::find(seen.begin(), seen.end(), key) != seen.end()) continue;
    if (!signal_series(r.steps, s.signal)) continue;
    seen.push_back(key);
    out.push_back(s);
    if (out.size() == count) break;
  }
  return out;
}

std::string header(const ReportData& r) {
  const solver::FitResult& fit = r.diagnosis.fit;
  const bool floor = fit.chi2_dof <= solver::kExplainedChi2Dof;
  std::string customs;
  for (const auto& c : r.request.customs) customs += " --custom " + c;
  return fmt::format(
      "<header><h1>Run {} &middot; {} &middot; {}</h1>\n"
      "<p>Model <code>{}</code>{}</p>\n"
      "<p>chi2/dof {:.3g} over {} steps<span class=\"badge {}\">{}</span></p>\n"
      "<p>{} fits in the history &middot; database {}</p></header>\n",
      r.request.run, html_escape(r.procedure), html_escape(r.device), html_escape(fit.model),
      customs.empty() ? "" : " with <code>" + html_escape(customs) + "</code>", fit.chi2_dof,
      fit.steps.size(), floor ? "good" : "bad",
      floor ? "at the noise floor"
            : fmt::format("{:.1f} &times; the noise", std::sqrt(fit.chi2_dof)),
      r.history.size(), html_escape(r.request.db));
}

// The run as `calstand runs` lists it, with its completed steps by kind.
std::string run_line(const ReportData& r) {
  std::string kinds;
  for (const auto& [kind, count] : r.step_kinds) {
    kinds += fmt::format("{}{} {}", kinds.empty() ? "" : ", ", count, kind);
  }
  return fmt::format("<p>{} &middot; {}/{} steps ({}) &middot; started {} &middot; ended {}</p>\n",
                     html_escape(r.run.status), r.run.steps_done, r.run.steps_total,
                     html_escape(kinds),
                     html_escape(r.run.started_utc.empty() ? "-" : r.run.started_utc),
                     html_escape(r.run.ended_utc.empty() ? "-" : r.run.ended_utc));
}

// The header of a run without an error model: what it is and what it holds.
std::string unfitted_header(const ReportData& r) {
  return fmt::format(
      "<header><h1>Run {} &middot; {} &middot; {}</h1>\n{}"
      "<p>No error model fitted<span class=\"badge neutral\">datasheet figures</span></p>\n"
      "<p>database {}</p></header>\n",
      r.request.run, html_escape(r.procedure), html_escape(r.device), run_line(r),
      html_escape(r.request.db));
}

std::string no_model_section(const ReportData& r) {
  return "<section id=\"model\" class=\"absent\"><h2>Error model</h2>\n<p class=\"dim\">Not "
         "fitted: " +
         html_escape(r.no_fit_reason) + ".</p></section>\n";
}

// The overview of the datasheet analyses and each one's figures; a line when none applies.
std::string datasheet_part(const ReportData& r) {
  const auto& ap = r.datasheet.applicability;
  if (std::none_of(ap.begin(), ap.end(), [](const auto& a) { return a.applies; })) {
    std::string why;
    for (const auto& a : ap) {
      why += fmt::format("{}{}: {}", why.empty() ? "" : "; ", to_string(a.kind), a.evidence);
    }
    return "<section id=\"datasheet\" class=\"absent\"><h2>Datasheet figures</h2>\n<p "
           "class=\"dim\">None of the test catalogue's analyses applies to this run (" +
           html_escape(why) + ").</p></section>\n";
  }
  return datasheet_overview_section(r.datasheet) + datasheet_sections(r);
}

std::string history_section(const ReportData& r) {
  return "<section id=\"history\"><h2>How the error fell</h2>\n"
         "<p class=\"lead\">chi2/dof of every fit of this run, oldest first, each labelled by the "
         "terms it added; at 1 the model explains the measurements down to their noise.</p>\n" +
         history_plot(r) + history_table(r) + "</section>\n";
}

std::string residual_section(const ReportData& r) {
  return fmt::format(
             "<section id=\"residuals\"><h2>Where the model fails</h2>\n"
             "<p class=\"lead\">Step-mean residual of each channel over its noise (z-score), "
             "step by step, coloured by <b>{}</b>. Within the dotted lines (|z| &lt; 2) the "
             "model fits.</p>\n",
             html_escape(r.grouping.kind)) +
         residual_plot(r) + groups_table(r) + "</section>\n";
}

std::string signals_section(const ReportData& r) {
  std::string out =
      "<section id=\"signals\"><h2>What the residual follows</h2>\n"
      "<p class=\"lead\">The residual of a channel against the signals it correlates with most "
      "(step means; colours as above, dashed: least-squares line). A clear trend names the "
      "missing effect.</p>\n<div class=\"grid\">\n";
  int rank = 0;
  for (const auto& s : top_signals(r, 3)) out += "<div>" + signal_plot(r, s, ++rank) + "</div>\n";
  return out + "</div>\n" + signals_table(r) + "</section>\n";
}

std::string parameters_section(const ReportData& r) {
  return "<section id=\"parameters\"><h2>Parameters and fit quality</h2>\n" + quality_table(r) +
         "<h3>Fitted parameters</h3>\n" + parameter_tables(r) + "</section>\n";
}

std::string candidates_section(const ReportData& r) {
  const auto& d = r.diagnosis;
  std::string out = advice_section_start(d.explained, d.advice);
  if (!d.candidates.empty()) {
    out +=
        "<p class=\"lead\">Each catalogue term the model lacks, added in turn and refitted, "
        "best change in BIC first.</p>\n" +
        candidate_plot(r);
  }
  return out + candidates_table(r) + "</section>\n";
}

std::string allan_section(const ReportData& r) {
  if (!r.noise) {
    return "<section id=\"allan\" class=\"absent\"><h2>Noise</h2>\n<p class=\"dim\">" +
           html_escape(r.noise_note) + ".</p></section>\n";
  }
  return fmt::format(
             "<section id=\"allan\"><h2>Noise: Allan deviation</h2>\n"
             "<p class=\"lead\">Overlapping Allan deviation of the longest static step ({} "
             "samples{}) with its confidence intervals, the fitted IEEE Std 952 model (solid) "
             "and its terms (dashed).</p>\n",
             r.noise->samples,
             r.noise->gaps ? fmt::format(", {} gaps in the device clock", r.noise->gaps) : "") +
         allan_plot(r, true) + allan_plot(r, false) +
         "<h3>Noise figures (datasheet units, &plusmn; one sigma; - not resolved)</h3>\n" +
         noise_figures_table(r, true) + noise_figures_table(r, false) + "</section>\n";
}

}  // namespace

std::string render_report_html(const ReportData& r) {
  std::string body;
  if (r.fitted()) {
    body += header(r);
    body += history_section(r);
    body += residual_section(r);
    body += signals_section(r);
    body += parameters_section(r);
    body += candidates_section(r);
  } else {
    body += unfitted_header(r);
    body += no_model_section(r);
  }
  body += datasheet_part(r);
  body += allan_section(r);
  if (r.static_record) {
    body += record_length_section(*r.static_record);
    body += noise_model_section(*r.static_record);
  }
  return report_page(r.request.run, r.procedure, body,
                     r.history.empty() ? r.run.ended_utc : r.history.back().created_utc);
}

ReportPage gather_report_page(store::Database& db, const ReportRequest& request) {
  ReportPage page;
  if (!needs_table_free_fit(db, request.run)) {
    page.table = gather_report(db, request);
    return page;
  }
  if (request.noise_run) throw_noise_run_on_table_free(request.run);
  if (solver::run_is_at_rest(db, request.run)) {
    page.static_record = gather_static_report(
        db, request,
        "the run lies at rest throughout (every step's gyros scatter like a unit at rest): it "
        "has no poses and no turns to calibrate from; a calibration without a table needs the "
        "unit turned between static poses (docs/guide-without-a-table.md)");
    return page;
  }
  try {
    page.table_free = gather_table_free_report(db, request);
    return page;
  } catch (const core::InputError& e) {
    // RunNotFound and the like, and a model such a run cannot fit, are the request's fault.
    if (typeid(e) != typeid(core::InputError) || e.where() == "model") throw;
    StaticReportData fallback = gather_static_report(db, request, e.what());
    if (!fallback.record) {
      throw core::InputError(
          e.where(), fmt::format("{}; nor has it a record at rest for a noise page ({})", e.what(),
                                 fallback.noise_note));
    }
    page.static_record = std::move(fallback);
    return page;
  }
}

std::string render_report_page(const ReportPage& page) {
  if (page.table) return render_report_html(*page.table);
  if (page.table_free) return render_table_free_report_html(*page.table_free);
  return render_static_report_html(page.static_record.value());
}

std::string run_report_html(store::Database& db, const ReportRequest& request) {
  find_gnuplot();  // before the work: a missing plotter is the first thing to say
  return render_report_page(gather_report_page(db, request));
}

}  // namespace calstand::analysis

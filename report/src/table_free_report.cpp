// The report page of a run without a table.
#include "report/table_free_report.hpp"

#include <fmt/format.h>

#include <cmath>

#include "render/gnuplot_svg.hpp"
#include "render/markup_escape.hpp"
#include "render/report_style.hpp"
#include "store/run_store.hpp"

namespace calstand::analysis {
namespace {

// The key sits top right on every plot of this page.
std::string terminal(int width, int height) {
  return svg_terminal(width, height) + "set key top right\n";
}

std::string optional_number(const std::optional<double>& v, const char* format) {
  return v ? fmt::format(fmt::runtime(format), *v) : std::string("-");
}

// |f| - g of every static pose with its 2-sigma noise band: a pose far outside it was not
// still, or the model lacks an effect of the accelerometers.
std::string pose_plot(const TableFreeFit& fit) {
  // The wander the pose means share (their noise model), RMS over the poses [mg].
  const double wander_mg = fit.accel->noise.pose_sigma / kMgInMps2;
  std::vector<std::string> rows;
  for (const auto& p : fit.accel->poses) {
    rows.push_back(fmt::format("{} {} {} {}", p.interval, gp_number(p.residual_mg),
                               gp_number(2.0 * p.sigma_mg),
                               gp_number(2.0 * std::hypot(p.sigma_mg, wander_mg))));
  }
  std::string s = terminal(1000, 360) + data_block("p", rows);
  s += "set xlabel 'static pose'\nset ylabel '|f| - g [mg]'\nset offsets 0.5, 0.5, 0, 0\n";
  s += "plot $p using 1:(0):4 with yerrorbars pt -1 lw 1.2 lc rgb '#c7d3df' "
       "title 'with the wander the poses share (2 sigma)', "
       "$p using 1:(0):3 with yerrorbars pt -1 lw 1.6 lc rgb '#7f8a96' "
       "title 'white noise of the pose mean (2 sigma)', "
       "$p using 1:2 with points pt 7 ps 1.1 lc rgb '#1f77b4' title '|f| - g'\n";
  return gnuplot_svg(s, "poses", "|f| - g at each static pose");
}

// The gravity direction after each turn: the integrated gyro against the accelerometers.
std::string turn_plot(const TableFreeFit& fit) {
  std::vector<std::string> rows;
  for (std::size_t k = 0; k < fit.gyro->turns.size(); ++k) {
    const auto& t = fit.gyro->turns[k];
    // The residual is an angle with two components of sigma_deg each (the turns' noise model),
    // scaled as the fit's sigmas are when the turns scatter more.
    rows.push_back(
        fmt::format("{} {} {}", k + 1, gp_number(t.residual_deg),
                    gp_number(2.0 * std::sqrt(2.0) * t.sigma_deg * fit.gyro->sigma_scale)));
  }
  std::string s = terminal(1000, 360) + data_block("t", rows);
  s += "set xlabel 'turn'\nset ylabel 'gravity direction off by [deg]'\nset yrange [0:*]\n";
  s += "set offsets 0.5, 0.5, 0, 0\n";
  s +=
      "plot $t using 1:3 with steps lw 1.2 lc rgb '#9aa5b1' title 'their scatter (about 2 sigma)', "
      "$t using 1:2 with points pt 7 ps 1.1 lc rgb '#d62728' title 'after the turn'\n";
  return gnuplot_svg(s, "turns", "gravity direction after each turn");
}

std::string header(const TableFreeReportData& r) {
  const TableFreeFit& fit = r.diagnosis.fit;
  const TableFreeQuality q = table_free_quality(fit);
  const bool good = r.diagnosis.explained && r.diagnosis.recommended.empty();
  return fmt::format(
      "<header><h1>Run {} &middot; {} &middot; {}</h1>\n"
      "<p>Recorded without a table &middot; method <b>{}</b> &middot; model <code>{}</code></p>\n"
      "<p>chi2/dof {} over {} degrees of freedom<span class=\"badge {}\">{}</span></p>\n"
      "<p>|f| - g rms {:.3g} mg{} &middot; {} fits in the history &middot; database {}</p>"
      "</header>\n",
      r.request.run, html_escape(r.procedure), html_escape(fit.device), html_escape(fit.method),
      html_escape(table_free_model_text(fit.terms)),
      q.dof > 0 ? fmt::format("{:.3g}", q.chi2_per_dof) : std::string("-"), q.dof,
      good ? "good" : "bad", good ? "explained" : "not explained",
      q.rms_norm_residual_mps2 / kMgInMps2,
      q.rms_turn_residual_deg
          ? fmt::format(" &middot; gravity direction after the turns {:.3g} deg rms",
                        *q.rms_turn_residual_deg)
          : std::string(),
      r.history.size(), html_escape(r.request.db));
}

std::string history_section(const TableFreeReportData& r) {
  std::string rows;
  for (const auto& f : r.history) {
    rows += fmt::format(
        "<tr><td class=\"num\">{}</td><td>{}</td><td>{}</td><td class=\"model\">{}</td>"
        "<td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td></tr>\n",
        f.id, html_escape(f.created_utc), html_escape(f.command), html_escape(f.model),
        optional_number(f.chi2_dof, "{:.3g}"),
        optional_number(
            f.rms_accel_mps2 ? std::optional<double>(*f.rms_accel_mps2 / kMgInMps2) : std::nullopt,
            "{:.3g}"),
        optional_number(f.rms_turn_deg, "{:.3g}"));
  }
  return "<section id=\"history\"><h2>How the error fell</h2>\n"
         "<p class=\"lead\">Every fit of this run, oldest first.</p>\n"
         "<table><thead><tr><th>fit</th><th>time</th><th>command</th><th>model</th>"
         "<th>chi2/dof</th><th>|f| - g rms [mg]</th><th>turns rms [deg]</th></tr></thead>"
         "<tbody>\n" +
         rows + "</tbody></table></section>\n";
}

std::string failure_section(const TableFreeReportData& r) {
  const TableFreeFit& fit = r.diagnosis.fit;
  std::string out =
      "<section id=\"residuals\"><h2>Where the model fails</h2>\n"
      "<p class=\"lead\">Each static pose's |calibrated f| against local g, and the gravity "
      "direction the calibrated gyro predicts after each turn against the one the "
      "accelerometers see, each with the noise it should stay within.</p>\n";
  if (fit.accel) out += pose_plot(fit);
  if (fit.gyro && !fit.gyro->turns.empty()) out += turn_plot(fit);
  if (fit.ferraris) {
    out +=
        "<table><thead><tr><th>hold</th><th>across the axis [deg]</th>"
        "<th>|f| - g [mg]</th></tr></thead><tbody>\n";
    for (const auto& h : fit.ferraris->holds) {
      out += fmt::format(
          "<tr><td>{}</td><td class=\"num\">{:.3g}</td>"
          "<td class=\"num\">{:.3g}</td></tr>\n",
          html_escape(h.label), h.across_residual_deg, h.norm_residual_mg);
    }
    out += "</tbody></table>\n";
  }
  if (!r.diagnosis.worst.empty()) {
    out +=
        "<h3>Worst poses and turns</h3><table><thead><tr><th>where</th><th>from [s]</th>"
        "<th>to [s]</th><th>residual</th><th>z</th></tr></thead><tbody>\n";
    for (const auto& w : r.diagnosis.worst) {
      out += fmt::format(
          "<tr><td>{}</td><td class=\"num\">{:.2f}</td><td class=\"num\">{:.2f}</td>"
          "<td class=\"num\">{:+.3g} {}</td><td class=\"num {}\">{:+.1f}</td></tr>\n",
          html_escape(w.what), w.start_s, w.end_s, w.residual, html_escape(w.unit),
          std::abs(w.z) > 3.0 ? "bad" : "good", w.z);
    }
    out += "</tbody></table>\n";
  }
  return out + "</section>\n";
}

std::string parameters_section(const TableFreeReportData& r) {
  const TableFreeFit& fit = r.diagnosis.fit;
  std::string rows;
  for (const auto& e : table_free_parameters(fit)) {
    const bool estimated = e.status == solver::EstimateStatus::kEstimated;
    rows += fmt::format(
        "<tr><td>{}</td><td class=\"num\">{:.6g}</td><td class=\"num\">{}</td><td>{}</td>"
        "<td class=\"dim\">{}</td></tr>\n",
        html_escape(e.name), e.value, estimated ? fmt::format("{:.3g}", e.sigma) : "-",
        html_escape(e.unit), estimated ? "" : solver::estimate_status_name(e.status));
  }
  std::string summaries;
  if (fit.accel) summaries += "<p>" + html_escape(fit.accel->summary) + "</p>\n";
  if (fit.gyro) summaries += "<p>" + html_escape(fit.gyro->summary) + "</p>\n";
  if (fit.ferraris) summaries += "<p>" + html_escape(fit.ferraris->summary) + "</p>\n";
  for (const auto& n : fit.notes) summaries += "<p class=\"dim\">" + html_escape(n) + "</p>\n";
  return "<section id=\"parameters\"><h2>Parameters and fit quality</h2>\n<p class=\"lead\">"
         "Frame: " +
         html_escape(solver::kAccelTriadFrameText) + ".</p>\n" + summaries +
         "<table><thead><tr><th>parameter</th><th>value</th><th>sigma</th><th>unit</th>"
         "<th></th></tr></thead><tbody>\n" +
         rows + "</tbody></table></section>\n";
}

std::string candidates_section(const TableFreeReportData& r) {
  const TableFreeDiagnosis& d = r.diagnosis;
  std::string out = advice_section_start(d.explained, d.advice);
  if (!d.candidates.empty()) {
    out +=
        "<table><thead><tr><th>term</th><th>sensor</th><th>delta BIC</th><th>p</th>"
        "<th>chi2/dof before</th><th>after</th><th>residual after</th></tr></thead><tbody>\n";
    for (const auto& c : d.candidates) {
      out += fmt::format(
          "<tr><td>{}</td><td>{}</td><td class=\"num\">{:.1f}</td><td class=\"num\">{:.2g}</td>"
          "<td class=\"num\">{:.3g}</td><td class=\"num\">{:.3g}</td><td>{}</td></tr>\n",
          html_escape(c.term), c.sensor, c.delta_bic, c.p_value, c.chi2_per_dof_before,
          c.chi2_per_dof_after, html_escape(c.residual_after));
    }
    out += "</tbody></table>\n";
  }
  for (const auto& u : d.untestable)
    out += "<p class=\"dim\">Not testable: " + html_escape(u) + "</p>\n";
  return out + "</section>\n";
}

std::string poses_section(const TableFreeReportData& r) {
  const TableFreeFit& fit = r.diagnosis.fit;
  if (!fit.poses) return "";
  const auto& d = fit.poses->detection;
  std::string rows;
  for (std::size_t i = 0; i < d.intervals.size(); ++i) {
    const auto& iv = d.intervals[i];
    rows += fmt::format(
        "<tr><td class=\"num\">{}</td><td class=\"num\">{:.2f}</td><td class=\"num\">{:.2f}</td>"
        "<td class=\"num\">{:.2f}</td><td class=\"num\">{:.4f} {:.4f} "
        "{:.4f}</td><td>{}</td></tr>\n",
        i, iv.start_s, iv.end_s, iv.duration_s(), iv.mean_accel_mps2.x(), iv.mean_accel_mps2.y(),
        iv.mean_accel_mps2.z(), iv.initial_rest ? "initial rest" : "");
  }
  return fmt::format("<section id=\"poses\"><h2>Static poses</h2>\n<p class=\"lead\">{}: {}.</p>\n",
                     fit.poses->given ? "given by the operator" : "found by the detector",
                     html_escape(d.rule_text)) +
         "<table><thead><tr><th>pose</th><th>start [s]</th><th>end [s]</th><th>length [s]</th>"
         "<th>mean accel x y z [m/s^2]</th><th></th></tr></thead><tbody>\n" +
         rows + "</tbody></table></section>\n";
}

}  // namespace

TableFreeReportData gather_table_free_report(store::Database& db, const ReportRequest& request) {
  TableFreeReportData r;
  r.request = request;
  TableFreeFitRequest fit_request =
      table_free_request(solver::Model::parse(request.model, request.customs), {});
  fit_request.device = request.device;
  fit_request.history_command = "report";
  r.diagnosis = diagnose_table_free(db, request.run, fit_request);
  r.procedure = store::RunStore(db).load_run(request.run).summary.procedure_name;
  r.history = store::fit_history(db, request.run);
  return r;
}

std::string render_table_free_report_html(const TableFreeReportData& r) {
  std::string body;
  body += header(r);
  body += history_section(r);
  body += failure_section(r);
  body += parameters_section(r);
  body += candidates_section(r);
  body += poses_section(r);
  return report_page(r.request.run, r.procedure, body,
                     r.history.empty() ? std::string() : r.history.back().created_utc);
}

}  // namespace calstand::analysis

#include "report/report_tables.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "html_cells.hpp"
#include "report/report_html.hpp"
#include "solver/groups.hpp"

namespace calstand::analysis {
namespace {

std::string optional_number(const std::optional<double>& v) {
  return v ? fmt::format("{:.3g}", *v) : std::string("&ndash;");
}

// A chi2/dof cell coloured by how far it is from the noise floor.
std::string chi2_cell(double chi2_dof) {
  const char* cls = chi2_dof <= solver::kExplainedChi2Dof ? "good"
                    : chi2_dof <= 5.0                     ? "warn"
                                                          : "bad";
  return fmt::format("<td class=\"num {}\">{:.3g}</td>", cls, chi2_dof);
}

using html_cells::row;

using html_cells::td;
std::string num_cell(std::string_view text) {
  return "<td class=\"num\">" + html_escape(text) + "</td>";
}

}  // namespace

std::string history_table(const ReportData& r) {
  std::string out =
      "<table><thead><tr><th>fit</th><th>time (UTC)</th><th>command</th><th>parameters</th>"
      "<th>chi2/dof</th><th>gyro rms [deg/s]</th><th>accel rms [m/s&sup2;]</th><th>model</th>"
      "</tr></thead><tbody>\n";
  for (std::size_t i = 0; i < r.history.size(); ++i) {
    const auto& f = r.history[i];
    std::string model = f.model;
    for (const auto& c : f.custom_terms) model += " (" + c + ")";
    out += row({td(r.history_labels[i]), td(f.created_utc), td(f.command),
                num_cell(std::to_string(f.parameters)),
                f.chi2_dof ? chi2_cell(*f.chi2_dof) : std::string("<td>&ndash;</td>"),
                "<td class=\"num\">" + optional_number(f.rms_gyro_dps) + "</td>",
                "<td class=\"num\">" + optional_number(f.rms_accel_mps2) + "</td>",
                "<td class=\"model\">" + html_escape(model) + "</td>"});
  }
  return out + "</tbody></table>\n";
}

std::string groups_table(const ReportData& r) {
  const auto& groups = r.diagnosis.groups;
  std::string out;
  if (!groups.empty()) {
    out +=
        "<table><thead><tr><th>group of steps</th><th>chi2/dof</th><th>steps</th></tr>"
        "</thead><tbody>\n";
    for (std::size_t i = 0; i < groups.size() && i < 8; ++i) {
      out += row({td(groups[i].group), chi2_cell(groups[i].chi2_dof),
                  num_cell(std::to_string(groups[i].steps.size()))});
    }
    out += "</tbody></table>\n";
  }
  const auto worst = solver::worst_steps(r.diagnosis.fit, 6);
  if (!worst.empty()) {
    out += "<p class=\"worst\">Worst single residuals: ";
    for (std::size_t i = 0; i < worst.size(); ++i) {
      out += fmt::format("{}step {} {} <b>z = {:+.1f}</b>", i ? "; " : "", worst[i].step,
                         html_escape(worst[i].channel), worst[i].z);
    }
    out += ".</p>\n";
  }
  return out;
}

std::string signals_table(const ReportData& r) {
  const auto& signals = r.diagnosis.signals;
  if (signals.empty()) return "<p>No signal varies over the steps of this run.</p>\n";
  std::string out =
      "<table><thead><tr><th>signal</th><th>channel</th><th>correlation r</th>"
      "</tr></thead><tbody>\n";
  for (std::size_t i = 0; i < signals.size() && i < 8; ++i) {
    out += row({td(signals[i].signal), td(signals[i].channel),
                num_cell(fmt::format("{:+.2f}", signals[i].correlation))});
  }
  return out + "</tbody></table>\n";
}

std::string quality_table(const ReportData& r) {
  const solver::FitResult& fit = r.diagnosis.fit;
  std::string out = fmt::format(
      "<p class=\"quality\">chi2/dof <b>{:.3g}</b> ({:.1f} over {} degrees of freedom): the "
      "step-mean residuals are <b>{:.2g}</b> times the noise. Noise floor from {} {}.</p>\n",
      fit.chi2_dof, fit.chi2, fit.dof, std::sqrt(std::max(fit.chi2_dof, 0.0)), fit.floor.steps_used,
      fit.floor.from_static_steps ? "static steps" : "steps (the run has no static step)");
  out +=
      "<table><thead><tr><th>sensor</th><th>step residual rms</th><th>noise floor x</th>"
      "<th>noise floor y</th><th>noise floor z</th><th>unit</th></tr></thead><tbody>\n";
  const auto used = solver::fit_channels(fit.rows);
  for (int sensor = 0; sensor < 2; ++sensor) {
    if (std::find(used.begin(), used.end(), sensor * 3) == used.end()) continue;
    const double rms = sensor == 0 ? fit.residual_rms_gyro_dps : fit.residual_rms_accel_mps2;
    out += row({td(sensor == 0 ? "gyro" : "accelerometer"), num_cell(fmt::format("{:.3g}", rms)),
                num_cell(fmt::format("{:.3g}", fit.noise_floor[sensor * 3])),
                num_cell(fmt::format("{:.3g}", fit.noise_floor[sensor * 3 + 1])),
                num_cell(fmt::format("{:.3g}", fit.noise_floor[sensor * 3 + 2])),
                td(sensor == 0 ? "deg/s" : "m/s^2")});
  }
  return out + "</tbody></table>\n";
}

std::string parameter_tables(const ReportData& r) {
  const solver::FitResult& fit = r.diagnosis.fit;
  std::string out =
      "<table><thead><tr><th>parameter</th><th>value</th><th>&plusmn; sigma</th>"
      "<th>unit</th><th>|value| / sigma</th></tr></thead><tbody>\n";
  for (const auto& p : fit.parameters) {
    const double significance = p.sigma > 0 ? std::abs(p.value) / p.sigma : 0.0;
    out += row({td(p.name), num_cell(fmt::format("{:.6g}", p.value)),
                num_cell(fmt::format("{:.2g}", p.sigma)), td(p.unit),
                fmt::format("<td class=\"num{}\">{:.1f}</td>", significance < 2.0 ? " dim" : "",
                            significance)});
  }
  out += "</tbody></table>\n";
  if (fit.unidentifiable.empty()) return out;
  out +=
      "<h3>Not determined by this run (held at zero)</h3>\n<table><thead><tr><th>parameter</th>"
      "<th>why</th><th>collinear with</th></tr></thead><tbody>\n";
  for (const auto& u : fit.unidentifiable) {
    std::string related;
    for (const auto& name : u.related) related += (related.empty() ? "" : ", ") + name;
    out += row({td(u.name), td(u.reason), td(related)});
  }
  return out + "</tbody></table>\n";
}

std::string candidates_table(const ReportData& r) {
  const auto& d = r.diagnosis;
  std::string out;
  if (!d.candidates.empty()) {
    out +=
        "<table><thead><tr><th>term</th><th>&Delta; BIC</th><th>p</th>"
        "<th>chi2/dof after</th><th>what it is</th></tr></thead><tbody>\n";
    for (std::size_t i = 0; i < d.candidates.size() && i < 15; ++i) {
      const auto& c = d.candidates[i];
      out += row({td(c.term), num_cell(fmt::format("{:.1f}", c.delta_bic)),
                  num_cell(fmt::format("{:.2g}", c.p_value)), chi2_cell(c.chi2_dof_after),
                  td(c.explanation)});
    }
    out += "</tbody></table>\n";
  }
  if (!d.untestable.empty()) {
    std::string names;
    for (const auto& u : d.untestable) names += (names.empty() ? "" : ", ") + u;
    out += "<p class=\"dim\">Not testable on this run: " + html_escape(names) + ".</p>\n";
  }
  return out;
}

std::string noise_figure_estimator(std::string_view name) {
  if (name == "bias_instability_min") {
    return "read off the overlapping Allan deviation: its minimum";
  }
  if (name == "bias_instability_min_coefficient") {
    return "read off the overlapping Allan deviation: minimum / 0.664 (IEEE Std 952)";
  }
  return "IEEE Std 952 model fitted to the overlapping Allan variance (weighted, non-negative "
         "least squares; from 20 sample periods)";
}

std::string noise_figures_table(const ReportData& r, bool gyro) {
  return r.noise ? noise_figures_table(*r.noise, gyro) : std::string();
}

std::string noise_figures_table(const solver::RunNoise& noise, bool gyro) {
  std::vector<const solver::ChannelNoise*> chans;
  for (const auto& c : noise.channels) {
    if (solver::is_gyro(c.channel) == gyro) chans.push_back(&c);
  }
  if (chans.empty()) return "";
  std::string out =
      fmt::format("<table><thead><tr><th>{}</th><th>unit</th>", gyro ? "gyro" : "accelerometer");
  for (const auto* c : chans) out += "<th>" + html_escape(solver::to_string(c->channel)) + "</th>";
  out += "<th>estimator</th></tr></thead><tbody>\n";
  for (std::size_t i = 0; i < chans.front()->figures.size(); ++i) {
    out += "<tr>" + td(chans.front()->figures[i].label) + td(chans.front()->figures[i].unit);
    for (const auto* c : chans) {
      if (i >= c->figures.size()) {
        out += "<td></td>";
        continue;
      }
      const auto& f = c->figures[i];
      out += num_cell(!f.resolved              ? std::string("-")
                      : std::isfinite(f.sigma) ? fmt::format("{:.3g} ± {:.2g}", f.value, f.sigma)
                                               : fmt::format("{:.3g}", f.value));
    }
    out += td(noise_figure_estimator(chans.front()->figures[i].name)) + "</tr>\n";
  }
  return out + "</tbody></table>\n";
}

}  // namespace calstand::analysis

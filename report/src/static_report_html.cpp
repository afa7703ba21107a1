// The page of a static record (static_report.hpp) as HTML: its sections in the order a lab
// engineer reads a noise test: what was recorded where, how long, the curves, the figures and
// their estimators, what the record is long enough for, the composite model, the stability.
#include <fmt/format.h>

#include <cmath>

#include "analysis/noise_model_json.hpp"
#include "html_cells.hpp"
#include "render/markup_escape.hpp"
#include "render/report_style.hpp"
#include "report/report_datasheet.hpp"
#include "report/report_plots.hpp"
#include "report/report_tables.hpp"
#include "report/static_report.hpp"

namespace calstand::analysis {
namespace {

using html_cells::td;

std::string static_num(std::string_view text) {
  return "<td class=\"num\">" + html_escape(text) + "</td>";
}

// A numeric cell of markup built from numbers (an entity such as &ndash; kept).
std::string static_markup(const std::string& markup) {
  return "<td class=\"num\">" + markup + "</td>";
}

std::string site_text(const nlohmann::json& site) {
  if (!site.is_object() || site.empty()) return "not recorded";
  const auto number = [&](const char* key, const char* format) {
    const nlohmann::json v = site.value(key, nlohmann::json());
    return v.is_number() ? fmt::format(fmt::runtime(format), v.get<double>()) : std::string("-");
  };
  return fmt::format("latitude {} deg, height {} m, gravity {} m/s&sup2;",
                     number("latitude_deg", "{:.6g}"), number("height_m", "{:.6g}"),
                     number("gravity_mps2", "{:.7g}"));
}

std::string static_header(const StaticReportData& r) {
  return fmt::format(
      "<header><h1>Run {} &middot; {} &middot; {}</h1>\n"
      "<p>{} &middot; started {} &middot; ended {}</p>\n"
      "<p>Site: {}</p>\n{}"
      "<p>A record at rest<span class=\"badge neutral\">noise and stability</span></p>\n"
      "<p>database {}</p></header>\n",
      r.request.run, html_escape(r.procedure), html_escape(r.device), html_escape(r.run.status),
      html_escape(r.run.started_utc.empty() ? "-" : r.run.started_utc),
      html_escape(r.run.ended_utc.empty() ? "-" : r.run.ended_utc), site_text(r.site),
      r.source.empty() ? "" : "<p>Source: " + html_escape(r.source) + "</p>\n",
      html_escape(r.request.db));
}

std::string calibration_section(const StaticReportData& r) {
  return "<section id=\"calibration\" class=\"absent\"><h2>Calibration</h2>\n<p "
         "class=\"dim\">Not made: " +
         html_escape(r.no_fit_reason) +
         ". This page is what the record gives: its noise and its stability.</p></section>\n";
}

std::string record_section(const StaticReportData& r) {
  if (!r.record) {
    return "<section id=\"record\" class=\"absent\"><h2>Record</h2>\n<p class=\"dim\">No noise "
           "analysis: " +
           html_escape(r.noise_note) + ".</p></section>\n";
  }
  const solver::RunNoise& n = r.record->noise;
  return fmt::format(
      "<section id=\"record\"><h2>Record</h2>\n<table><tbody>\n"
      "<tr><th>analysed</th><td>{}</td></tr>\n"
      "<tr><th>length</th><td class=\"num\">{} ({:.1f} s)</td></tr>\n"
      "<tr><th>samples</th><td class=\"num\">{}</td></tr>\n"
      "<tr><th>sample rate</th><td class=\"num\">{:.6g} Hz</td></tr>\n"
      "<tr><th>gaps in the device clock</th><td class=\"num\">{}</td></tr>\n"
      "</tbody></table></section>\n",
      html_escape(r.record_label), html_escape(solver::format_record_length(n.duration_s)),
      n.duration_s, n.samples, n.sample_rate_hz, n.gaps);
}

std::string allan_part(const StaticRecordNoise& s) {
  return "<section id=\"allan\"><h2>Noise: Allan deviation</h2>\n"
         "<p class=\"lead\">Overlapping Allan deviation of every channel at dense averaging "
         "times, with its 68.3 % confidence intervals (equivalent degrees of freedom of the "
         "noise type at each tau), the fitted IEEE Std 952 model (solid) and its terms "
         "(dashed). <code>calstand noise</code> gives the same figures.</p>\n" +
         allan_plot(s.noise, true) + allan_plot(s.noise, false) +
         "<h3>Noise figures (datasheet units, &plusmn; one sigma; - not resolved)</h3>\n" +
         noise_figures_table(s.noise, true) + noise_figures_table(s.noise, false) + "</section>\n";
}

}  // namespace

std::string record_length_section(const StaticRecordNoise& s) {
  const solver::RecordLengthRule rule;
  std::string out = fmt::format(
      "<section id=\"record-length\"><h2>Is the record long enough?</h2>\n<p class=\"lead\">This "
      "record has {}. What each figure needs for its {:.0f} % interval within &plusmn;{:.0f} % "
      "(the Allan variance's equivalent degrees of freedom reach {:.0f} at the figure's "
      "tau).</p>\n<table><thead><tr><th>sensor</th><th>figure</th><th>read at &tau; "
      "[s]</th><th>axis</th><th>needs</th><th>verdict</th></tr></thead><tbody>\n",
      html_escape(solver::format_record_length(s.noise.duration_s)), 100.0 * rule.confidence,
      100.0 * rule.half_width, solver::required_edf(rule));
  for (const solver::FigureRecordNeed& n : s.record_needs) {
    const std::string label = n.figure == "random_walk"
                                  ? (n.gyro ? "angle random walk" : "velocity random walk")
                              : n.figure == "bias_instability"
                                  ? "bias instability"
                                  : (n.gyro ? "rate random walk" : "acceleration random walk");
    out += "<tr>" + td(n.gyro ? "gyro" : "accelerometer") + td(label) +
           static_num(fmt::format("{:.3g}", n.tau_s)) + td(n.channel) +
           static_num((n.located ? "about " : "more than ") +
                      solver::format_record_length(n.needed_s)) +
           fmt::format("<td class=\"{}\">{}</td>", n.enough ? "good" : "bad",
                       n.enough ? "enough"
                                : html_escape("not enough: this record has " +
                                              solver::format_record_length(n.record_length_s))) +
           "</tr>\n";
  }
  return out + "</tbody></table></section>\n";
}

std::string noise_model_section(const StaticRecordNoise& s) {
  std::string estimator, selected_by;
  for (const auto& m : s.models) {
    if (m.model) {
      estimator = m.model->estimator;
      selected_by = m.model->selected_by;
      break;
    }
  }
  std::string out =
      "<section id=\"noise-model\"><h2>Composite noise model</h2>\n<p class=\"lead\">The terms "
      "each channel's record supports, identified together (<code>calstand noise-id</code>, the "
      "same model, values and intervals): " +
      html_escape(estimator.empty() ? std::string("-") : estimator) + "; selected by " +
      html_escape(selected_by.empty() ? std::string("-") : selected_by) +
      ".</p>\n<table><thead><tr><th>channel</th><th>term</th><th>parameter</th><th>value</th>"
      "<th>95 % interval</th><th>unit</th></tr></thead><tbody>\n";
  for (const ChannelNoiseModel& m : s.models) {
    const std::string channel(solver::to_string(m.channel));
    const std::string unit(solver::channel_unit(m.channel));
    if (!m.model) {
      out += "<tr>" + td(channel) + "<td colspan=\"5\" class=\"dim\">" + html_escape(m.note) +
             "</td></tr>\n";
      continue;
    }
    for (const solver::NoiseModelTerm& t : m.model->terms) {
      const auto row = [&](const std::string& name, double v, double lo, double hi,
                           const std::string& u) {
        out += "<tr>" + td(channel) + td(std::string(solver::to_string(t.kind))) + td(name) +
               static_num(fmt::format("{:.4g}", v)) +
               static_markup(fmt::format("{:.4g} &ndash; {:.4g}", lo, hi)) + td(u) + "</tr>\n";
      };
      row(noise_parameter_name(t.kind), t.value, t.value_lo, t.value_hi,
          noise_parameter_unit(t.kind, unit));
      if (t.kind == solver::NoiseKind::kGaussMarkov) {
        row("tau_s", t.tau_s, t.tau_lo_s, t.tau_hi_s, "s");
      }
    }
  }
  return out + "</tbody></table></section>\n";
}

namespace {

std::string stability_part(const StaticRecordNoise& s) {
  if (s.stability) return stability_section(*s.stability);
  return "<section id=\"datasheet-stability\" class=\"absent\"><h2>In-run bias stability</h2>\n"
         "<p class=\"dim\">" +
         html_escape(s.stability_note) + ".</p></section>\n";
}

}  // namespace

std::string render_static_report_html(const StaticReportData& r) {
  std::string body = static_header(r) + calibration_section(r) + record_section(r);
  if (r.record) {
    body += allan_part(*r.record);
    body += record_length_section(*r.record);
    body += noise_model_section(*r.record);
    body += stability_part(*r.record);
  }
  return report_page(r.request.run, r.procedure, body, r.run.ended_utc);
}

}  // namespace calstand::analysis

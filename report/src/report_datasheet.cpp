#include "report/report_datasheet.hpp"

#include <fmt/format.h>

#include <cmath>
#include <initializer_list>
#include <string>
#include <string_view>

#include "core/units.hpp"
#include "html_cells.hpp"
#include "render/markup_escape.hpp"
#include "report/report_datasheet_plots.hpp"

namespace calstand::analysis {
namespace {

constexpr double kHysteresisZ = 4.0;  ///< |z| beyond this: the difference is hysteresis

using html_cells::td;
// A numeric cell of markup the caller built from numbers (entities such as &plusmn; kept).
std::string num(std::string_view markup, std::string_view cls = "") {
  return fmt::format("<td class=\"num{}{}\">{}</td>", cls.empty() ? "" : " ", cls, markup);
}
using html_cells::row;
std::string head(std::initializer_list<std::string_view> names) {
  std::string out = "<table><thead><tr>";
  for (const auto n : names) out += "<th>" + std::string(n) + "</th>";
  return out + "</tr></thead><tbody>\n";
}
constexpr const char* kTableEnd = "</tbody></table>\n";

const char* sensor_unit(std::size_t channel) { return channel < 3 ? "deg/h" : "ug"; }
std::string n(double value, int digits = 3) { return datasheet_number(value, digits); }
std::string interval(double lo, double hi) { return n(lo) + " &ndash; " + n(hi); }
std::string plus_minus(double value, double sigma, int digits) {
  return n(value, digits) + " &plusmn; " + n(sigma, 2);
}

std::string section_start(DatasheetKind kind, const std::string& lead) {
  return fmt::format("<section id=\"datasheet-{}\"><h2>{}</h2>\n<p class=\"lead\">{}</p>\n",
                     to_string(kind), title(kind), lead);
}

// --- repeatability -------------------------------------------------------------------------

/// The gyro scale factor's repeatability where the cycles turn both ways about an axis.
std::string scale_repeatability_table(const RepeatabilityAnalysis& r) {
  std::string rows;
  for (std::size_t a = 0; a < r.gyro_scale.size(); ++a) {
    const ScaleRepeatability& s = r.gyro_scale[a];
    if (!s.measured) continue;
    std::string rates;
    for (double rate : s.rates_dps) rates += (rates.empty() ? "" : ", ") + n(rate);
    rows += row({td(fmt::format("g{}", "xyz"[a])), num(n(s.repeatability_ppm)),
                 num(interval(s.repeatability_lo_ppm, s.repeatability_hi_ppm)),
                 num(n(s.spread_ppm)), num(n(s.noise_of_estimates_ppm)), num(rates)});
  }
  if (rows.empty()) return "";
  return "<p>Gyro scale factor: each cycle's (mean at +r &minus; mean at &minus;r) / 2r about "
         "each body axis, its spread over the cycles less the white noise of one estimate, in "
         "ppm.</p>\n" +
         head({"axis", "scale-factor repeatability (1&sigma;, ppm)",
               fmt::format("{:.0f} % interval", 100.0 * r.confidence), "spread", "noise of one",
               "rates (deg/s)"}) +
         rows + kTableEnd;
}

std::string repeatability_section(const RepeatabilityAnalysis& r) {
  std::string out = section_start(
      DatasheetKind::kRepeatability,
      fmt::format("Turn-on bias over {} power cycles, {} position{} each ({} degrees of "
                  "freedom): the spread of the static means from one power-up to the next less "
                  "the noise of a mean, sqrt(spread&sup2; &minus; noise&sup2;), 1 sigma, with its "
                  "{:.0f} % interval (chi-square). <code>calstand analyze repeatability</code>",
                  r.cycles, r.positions, r.positions == 1 ? "" : "s", r.dof, 100.0 * r.confidence));
  out += head({"channel", "bias repeatability (1&sigma;)",
               fmt::format("{:.0f} % interval", 100.0 * r.confidence), "spread of the means",
               "noise of a mean", "unit"});
  for (std::size_t c = 0; c < r.channels.size(); ++c) {
    const ChannelRepeatability& ch = r.channels[c];
    out += row({td(ch.channel), num(n(ch.repeatability)),
                num(interval(ch.repeatability_lo, ch.repeatability_hi)), num(n(ch.spread)),
                num(n(ch.noise_of_means)), td(sensor_unit(c))});
  }
  out += kTableEnd + scale_repeatability_table(r);
  return out + repeatability_plot(r) + "</section>\n";
}

// --- warm-up -------------------------------------------------------------------------------

std::string warmup_section(const WarmupAnalysis& w, const std::optional<WarmupSeries>& series) {
  std::string out = section_start(
      DatasheetKind::kWarmup,
      fmt::format("Step {} ({}): {:.0f} s from power-up, fitted per axis as settled value + A "
                  "exp(&minus;t/&tau;){} in bins of {:.3g} s; the IMU warmed by {:.2f} degC. "
                  "Time to band: until |A| exp(&minus;t/&tau;) stays within {:g} deg/h (gyros) "
                  "or {:g} ug (accelerometers). <code>calstand analyze warmup</code>",
                  w.step, html_escape(w.step_label), w.duration_s,
                  w.with_temperature ? " + k (T &minus; T<sub>end</sub>)" : "", w.bin_s,
                  w.temperature_rise_c, w.band_deg_per_h, w.band_ug));
  out += head({"channel", "transient amplitude A &plusmn; 1&sigma;", "time constant &tau; [s]",
               "time to band [s]", "unit", ""});
  for (std::size_t c = 0; c < w.channels.size(); ++c) {
    const ChannelWarmup& ch = w.channels[c];
    // Without a resolved transient tau means nothing (warmup.hpp): its cells say so.
    out += row({td(ch.channel), num(plus_minus(ch.amplitude, ch.amplitude_sigma, 3)),
                num(ch.resolved ? n(ch.time_constant_s) : "&ndash;"),
                num(ch.resolved ? fmt::format("{:.0f}", ch.time_to_band_s) : "&ndash;"),
                td(sensor_unit(c)),
                td(!ch.resolved          ? "no transient resolved"
                   : ch.temperature_term ? "with a temperature term"
                                         : "")});
  }
  out += kTableEnd;
  if (series) out += warmup_plot(w, *series);
  return out + "</section>\n";
}

// --- stability -----------------------------------------------------------------------------

// The Allan floor: a bound ("<") when the curve never turned up inside the record.
std::string bias_instability_cells(const ChannelStability& ch) {
  return num((ch.floor_resolved ? "" : "&lt; ") + n(ch.bias_instability)) +
         num(interval(ch.bias_instability_lo, ch.bias_instability_hi)) + num(n(ch.min_tau_s));
}

// The bias model the Allan curve shows, then the Gauss-Markov bias variation and its correlation
// time: a datasheet figure only where that model is chosen (stability.hpp).
std::string bias_variation_cells(const ChannelStability& ch) {
  const std::string model = "<td title=\"" + html_escape(ch.bias_model_reason) + "\">" +
                            html_escape(solver::to_string(ch.bias_model)) + "</td>";
  if (!ch.variation_sigma || !ch.correlation_time_s) {
    return model + num("&ndash;", "dim") + num("&ndash;", "dim");
  }
  return model + num(n(*ch.variation_sigma)) +
         num(n(*ch.correlation_time_s), ch.correlation_resolved ? "" : "dim");
}

}  // namespace

std::string stability_section(const StabilityAnalysis& s) {
  std::string out = section_start(
      DatasheetKind::kStability,
      fmt::format("Step {} ({}): {:.0f} s static. Bias instability: the Allan deviation's "
                  "minimum / 0.664 (IEEE 952) with that point's {:.0f} % interval; "
                  "&lt;: no floor inside the record, a bound. Bias model: a Gauss-Markov bias or a "
                  "flicker floor, whichever the Allan curve supports by AIC (undecided: neither; "
                  "hover for why). Bias variation: the sigma and correlation time of the "
                  "Gauss-Markov bias, only where it is chosen (grey: the correlation time is "
                  "outside what the record shows). <code>calstand analyze stability</code>",
                  s.step, html_escape(s.step_label), s.duration_s, 100.0 * s.confidence));
  out += head({"channel", "bias instability",
               fmt::format("{:.0f} % interval", 100.0 * s.confidence), "at &tau; [s]", "bias model",
               "bias variation (1&sigma;)", "correlation time [s]", "unit"});
  for (std::size_t c = 0; c < s.channels.size(); ++c) {
    const ChannelStability& ch = s.channels[c];
    out += "<tr>" + td(ch.channel) + bias_instability_cells(ch) + bias_variation_cells(ch) +
           td(sensor_unit(c)) + "</tr>\n";
  }
  return out + kTableEnd + "</section>\n";
}

namespace {

// --- hysteresis ----------------------------------------------------------------------------

std::string hysteresis_section(const HysteresisAnalysis& h) {
  std::string ends;
  if (!h.up_only_c.empty()) {
    ends += fmt::format(" Only on the way up: {} degC.", fmt::join(h.up_only_c, ", "));
  }
  if (!h.down_only_c.empty()) {
    ends += fmt::format(" Only on the way down: {} degC.", fmt::join(h.down_only_c, ", "));
  }
  std::string out = section_start(
      DatasheetKind::kHysteresis,
      fmt::format("<code>{}</code> fitted at each set point on the way up and on the way down "
                  "(the run's own noise model), &plusmn; 1 sigma; the difference beside its "
                  "uncertainty: |z| &gt; {:g} (red) is hysteresis.{} <code>calstand analyze "
                  "hysteresis</code>",
                  html_escape(h.model), kHysteresisZ, ends));
  out += head({"set point [degC]", "parameter", "up", "down", "up &minus; down", "z", "unit"});
  for (const HysteresisPoint& p : h.points) {
    const ParameterScale u = parameter_scale(p.unit);
    out += row({num(fmt::format("{:g}", p.temperature_c)), td(p.parameter),
                num(plus_minus(u.factor * p.up, u.factor * p.up_sigma, 4)),
                num(plus_minus(u.factor * p.down, u.factor * p.down_sigma, 4)),
                num(plus_minus(u.factor * p.difference, u.factor * p.difference_sigma, 3)),
                num(fmt::format("{:+.1f}", p.z), std::abs(p.z) > kHysteresisZ ? "bad" : ""),
                td(u.unit)});
  }
  return out + kTableEnd + hysteresis_plot(h) + "</section>\n";
}

// --- bandwidth -----------------------------------------------------------------------------

// The value, then its interval ("&ndash;" when the bootstrap lost too many draws).
std::string bandwidth_cell(const BandwidthAnalysis& b, std::size_t axis) {
  const auto& fc = b.bandwidth_hz[axis];
  if (!fc) return num("beyond the frequencies tested", "dim") + num("&ndash;", "dim");
  const auto& ci = b.bandwidth_interval_hz[axis];
  return num(n(*fc, 4)) + (ci ? num(interval((*ci)[0], (*ci)[1])) : num("&ndash;", "dim"));
}

std::string delay_cell(const BandwidthAnalysis& b, std::size_t axis) {
  const auto& tau = b.delay_s[axis];
  if (!tau) return num("&ndash;", "dim") + num("&ndash;", "dim");
  const auto& ci = b.delay_interval_s[axis];
  return num(n(*tau * 1e3)) +
         (ci ? num(interval((*ci)[0] * 1e3, (*ci)[1] * 1e3)) : num("&ndash;", "dim"));
}

std::string bandwidth_section(const BandwidthAnalysis& b) {
  std::string out = section_start(
      DatasheetKind::kBandwidth,
      "Each gyro against the table encoder, oscillating about its axis: the -3 dB frequency "
      "on the gain curve and the output delay (the phase left after the low-pass model's, "
      "against angular frequency). <code>calstand analyze bandwidth</code>");
  const std::string ci = fmt::format("{:.0f} % interval", 100.0 * b.confidence);
  out += head({"axis", "-3 dB bandwidth [Hz]", ci, "delay [ms]", ci, "low-pass model"});
  for (std::size_t axis = 0; axis < 3; ++axis) {
    bool oscillated = false;
    for (const auto& p : b.points) oscillated = oscillated || p.axis == static_cast<int>(axis);
    if (!oscillated) continue;
    const int order = b.low_pass_order[axis];
    out += "<tr>" + td(std::string(1, static_cast<char>('x' + axis))) + bandwidth_cell(b, axis) +
           delay_cell(b, axis) +
           td(order > 0 ? fmt::format("Butterworth, order {}", order) : "none removed") + "</tr>\n";
  }
  // The gain plot is drawn 700 px wide: at the page's full width its text would be oversized.
  out += std::string(kTableEnd) + "<div class=\"narrow\">" + bandwidth_svg(b) + "</div>\n";
  out += "<h3>Gain and phase at each frequency</h3>\n";
  out += head({"axis", "frequency [Hz]", "gain", "gain [dB]", "phase [deg]", "step"});
  for (const BandwidthPoint& p : b.points) {
    out += row({td(std::string(1, static_cast<char>('x' + p.axis))),
                num(fmt::format("{:g}", p.frequency_hz)), num(fmt::format("{:.4f}", p.gain)),
                num(fmt::format("{:.2f}", p.gain_db)), num(fmt::format("{:.1f}", p.phase_deg)),
                td(fmt::format("{} ({})", p.step, p.label))});
  }
  return out + kTableEnd + "</section>\n";
}

}  // namespace

std::string datasheet_number(double value, int digits) {
  if (!std::isfinite(value)) return fmt::format("{}", value);
  if (value == 0.0) return "0";
  const int magnitude = static_cast<int>(std::floor(std::log10(std::abs(value))));
  if (magnitude < -3 || magnitude >= 6) return fmt::format("{:.{}g}", value, digits);
  return fmt::format("{:.{}f}", value, std::max(0, digits - 1 - magnitude));
}

ParameterScale parameter_scale(const std::string& unit) {
  if (unit == "deg/s") return {core::convert(1.0, "deg/s", "deg/h"), "deg/h"};
  if (unit == "m/s^2") return {core::convert(1.0, "m/s^2", "ug"), "ug"};
  return {1.0, unit};
}

std::string datasheet_overview_section(const DatasheetAnalyses& a) {
  std::string out =
      "<section id=\"datasheet\"><h2>Datasheet figures</h2>\n<p class=\"lead\">The analyses of "
      "the test catalogue (<code>calstand analyze KIND</code>) this run's steps support; each "
      "one below in datasheet units with its interval.</p>\n";
  out += head({"analysis", "", "from this run"});
  for (const DatasheetApplicability& ap : a.applicability) {
    const std::string name =
        fmt::format("{} (<code>{}</code>)", title(ap.kind), to_string(ap.kind));
    if (!ap.applies) {
      out += "<tr class=\"dim\"><td>" + name + "</td><td>not applicable</td>" + td(ap.evidence) +
             "</tr>\n";
    } else if (a.has_result(ap.kind)) {
      out += fmt::format(
          "<tr><td><a href=\"#datasheet-{}\">{}</a></td><td class=\"good\">below"
          "</td>{}</tr>\n",
          to_string(ap.kind), name, td(ap.evidence));
    } else {
      out += "<tr><td>" + name + "</td><td class=\"bad\">missing</td>" +
             td(ap.evidence + ", but the analysis refused it: " + a.failure_of(ap.kind)) +
             "</tr>\n";
    }
  }
  return out + kTableEnd + "</section>\n";
}

std::string datasheet_sections(const ReportData& r) {
  const DatasheetAnalyses& a = r.datasheet;
  std::string out;
  for (const DatasheetKind kind : kDatasheetKinds) {
    switch (kind) {
      case DatasheetKind::kRepeatability:
        if (a.repeatability) out += repeatability_section(*a.repeatability);
        break;
      case DatasheetKind::kWarmup:
        if (a.warmup) out += warmup_section(*a.warmup, r.warmup_series);
        break;
      case DatasheetKind::kStability:
        if (a.stability) out += stability_section(*a.stability);
        break;
      case DatasheetKind::kHysteresis:
        if (a.hysteresis) out += hysteresis_section(*a.hysteresis);
        break;
      case DatasheetKind::kBandwidth:
        if (a.bandwidth) out += bandwidth_section(*a.bandwidth);
        break;
    }
  }
  return out;
}

}  // namespace calstand::analysis

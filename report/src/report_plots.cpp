#include "report/report_plots.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "noise/noise_fit.hpp"
#include "render/gnuplot_svg.hpp"
#include "solver/groups.hpp"

namespace calstand::analysis {
namespace {

// Colour-blind-safe enough, and distinct on white (Tableau 10).
constexpr std::array<const char*, 10> kPalette = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                                  "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                                                  "#bcbd22", "#17becf"};

const char* colour(std::size_t i) { return kPalette[i % kPalette.size()]; }

int channel_index(const std::string& name) {
  for (int c = 0; c < solver::kChannels; ++c) {
    if (solver::channel_name(c) == name) return c;
  }
  return -1;
}

}  // namespace

std::string history_plot(const ReportData& r) {
  std::vector<std::string> rows;
  for (std::size_t i = 0; i < r.history.size(); ++i) {
    const auto& f = r.history[i];
    const double chi2 = f.chi2_dof ? std::max(*f.chi2_dof, 1e-6) : std::nan("");
    rows.push_back(fmt::format("{} {} {}", i + 1, gp_number(chi2), data_text(r.history_labels[i])));
  }
  std::string s = svg_terminal(1000, 420) + data_block("h", rows);
  s += fmt::format("set logscale y\nset xrange [0.5:{}]\n",
                   static_cast<double>(r.history.size()) + 0.5);
  s += "set ylabel 'chi2 / dof'\nset xtics rotate by 20 right font ',11'\nset bmargin 7\n";
  s += "set offsets 0, 0, graph 0.12, graph 0.05\nset key top right\n";
  s += horizontal_line(1.0, "#2ca02c", 2);
  s += "set label 'noise floor (chi2/dof = 1)' at graph 0.01, first 1 offset 0,0.7 "
       "textcolor rgb '#2ca02c'\n";
  s += "plot $h using 1:2:xtic(3) with linespoints lw 2.5 pt 7 ps 1.3 lc rgb '#1f77b4' "
       "title 'chi2/dof of each fit', "
       "$h using 1:2:(sprintf('%.3g', $2)) with labels offset 0,1.1 textcolor rgb '#1f4e79' "
       "notitle\n";
  return gnuplot_svg(s, "history", "chi2/dof of each fit of the run");
}

std::string residual_plot(const ReportData& r) {
  const solver::FitResult& fit = r.diagnosis.fit;
  const std::vector<int> channels = solver::fit_channels(fit.rows);
  const bool gyro = std::any_of(channels.begin(), channels.end(), [](int c) { return c < 3; });
  const bool accel = std::any_of(channels.begin(), channels.end(), [](int c) { return c >= 3; });
  const int panels = (gyro ? 1 : 0) + (accel ? 1 : 0);
  constexpr std::array<int, 3> kShape = {7, 9, 5};  // x circle, y triangle, z square
  constexpr std::array<double, 3> kOffset = {-0.22, 0.0, 0.22};

  std::string s = svg_terminal(1000, 330 * panels + 20);
  double max_index = 0.0;
  for (const auto& st : fit.steps) max_index = std::max(max_index, static_cast<double>(st.index));
  for (int sensor = 0; sensor < 2; ++sensor) {
    if ((sensor == 0 && !gyro) || (sensor == 1 && !accel)) continue;
    for (std::size_t g = 0; g < r.grouping.values.size(); ++g) {
      std::vector<std::string> rows;
      for (std::size_t i = 0; i < fit.steps.size(); ++i) {
        if (r.grouping.value_index(i) != g) continue;
        const solver::Vector6d z = fit.steps[i].z();
        for (int axis = 0; axis < 3; ++axis) {
          const double v = z[sensor * 3 + axis];
          if (!std::isfinite(v)) continue;
          rows.push_back(fmt::format("{} {} {}",
                                     static_cast<double>(fit.steps[i].index) + kOffset[axis],
                                     gp_number(v), kShape[axis]));
        }
      }
      if (rows.empty()) rows.push_back("NaN NaN 7");  // keeps the legend entry
      s += data_block(fmt::format("s{}g{}", sensor, g), rows);
    }
  }
  s += fmt::format("set multiplot layout {},1\n", panels);
  s += fmt::format("set xrange [-0.5:{}]\nset xlabel 'step'\n", max_index + 0.5);
  s += "set yrange [*<-2.5:2.5<*]\n";  // the |z| = 2 lines always inside
  s += fmt::format("set key outside right top title {} box lc rgb '#cccccc'\n",
                   gnuplot_quote(r.grouping.kind));
  s += horizontal_line(0.0, "#555555", 1) + horizontal_line(2.0, "#999999", 3) +
       horizontal_line(-2.0, "#999999", 3);
  for (int sensor = 0; sensor < 2; ++sensor) {
    if ((sensor == 0 && !gyro) || (sensor == 1 && !accel)) continue;
    s += fmt::format("set ylabel '{} residual z'\n", sensor == 0 ? "gyro" : "accel");
    s += fmt::format(
        "set title '{}: step-mean residual / step noise (x circle, y triangle, z "
        "square)'\n",
        sensor == 0 ? "gyro" : "accelerometer");
    std::string plot = "plot ";
    for (std::size_t g = 0; g < r.grouping.values.size(); ++g) {
      plot +=
          fmt::format("{}$s{}g{} using 1:2:3 with points pt variable ps 0.9 lc rgb '{}' notitle",
                      g ? ", " : "", sensor, g, colour(g));
    }
    // Legend entries of their own: a point-type-variable sample is drawn as a dot.
    for (std::size_t g = 0; g < r.grouping.values.size(); ++g) {
      plot += fmt::format(", keyentry with points pt 7 ps 1.2 lc rgb '{}' title {}", colour(g),
                          gnuplot_quote(r.grouping.values[g]));
    }
    s += plot + "\n";
  }
  s += "unset multiplot\n";
  return gnuplot_svg(s, "residuals", "step-mean residuals per step");
}

std::string signal_plot(const ReportData& r, const solver::SignalCorrelation& signal, int rank) {
  const auto x = signal_series(r.steps, signal.signal);
  const int c = channel_index(signal.channel);
  const auto& fit_steps = r.diagnosis.fit.steps;
  if (!x || c < 0 || x->size() != fit_steps.size()) return "";
  std::string s = svg_terminal(420, 360);
  s += "set xtics font ',10'\nset ytics font ',10'\nset format x '%.3g'\nset xtics rotate by 30 "
       "right\n";
  // Least-squares line of z on the signal, over the finite points.
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t g = 0; g < r.grouping.values.size(); ++g) {
    std::vector<std::string> rows;
    for (std::size_t i = 0; i < fit_steps.size(); ++i) {
      const double zi = fit_steps[i].z()[c];
      const double xi = (*x)[i];
      if (r.grouping.value_index(i) != g || !std::isfinite(zi) || !std::isfinite(xi)) continue;
      rows.push_back(fmt::format("{} {}", gp_number(xi), gp_number(zi)));
      n += 1;
      sx += xi;
      sy += zi;
      sxx += xi * xi;
      sxy += xi * zi;
    }
    if (rows.empty()) rows.push_back("NaN NaN");
    s += data_block(fmt::format("g{}", g), rows);
  }
  const double det = n * sxx - sx * sx;
  const double slope = det > 0 ? (n * sxy - sx * sy) / det : 0.0;
  const double intercept = n > 0 ? (sy - slope * sx) / n : 0.0;
  s += fmt::format("set title {} font ',13'\n",
                   gnuplot_quote(fmt::format("{} vs {}: r = {:+.2f}", signal.channel, signal.signal,
                                             signal.correlation)));
  s += fmt::format("set xlabel {}\nset ylabel {}\nset key off\n",
                   gnuplot_quote("step mean of " + signal.signal),
                   gnuplot_quote(signal.channel + " residual z"));
  s += "set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05\n";
  s += horizontal_line(0.0, "#555555", 1);
  std::string plot = "plot ";
  for (std::size_t g = 0; g < r.grouping.values.size(); ++g) {
    plot += fmt::format("$g{} using 1:2 with points pt 7 ps 0.9 lc rgb '{}', ", g, colour(g));
  }
  plot += fmt::format("{} + {} * x with lines lw 2 dt 2 lc rgb '#333333'\n", gp_number(intercept),
                      gp_number(slope));
  return gnuplot_svg(s + plot, fmt::format("signal{}", rank),
                     fmt::format("{} residual against {}", signal.channel, signal.signal));
}

std::string candidate_plot(const ReportData& r) {
  const auto& d = r.diagnosis;
  const std::size_t count = std::min<std::size_t>(d.candidates.size(), 12);
  std::vector<std::string> rows;
  for (std::size_t i = 0; i < count; ++i) {
    const auto& c = d.candidates[i];
    const int rgb = c.delta_bic < 0 ? 0x2ca02c : 0xaaaaaa;
    rows.push_back(fmt::format("{} {} {} {}", i + 1, gp_number(std::max(c.chi2_dof_after, 1e-6)),
                               data_text(c.term), rgb));
  }
  std::string s = svg_terminal(1000, 400) + data_block("c", rows);
  s += fmt::format("set logscale y\nset xrange [0.4:{}]\n", static_cast<double>(count) + 0.6);
  s += "set ylabel 'chi2 / dof after adding'\nset xtics rotate by 20 right font ',11'\n";
  s += "set bmargin 7\nset key top right\nset style fill solid 0.85 noborder\nset boxwidth 0.6\n";
  s += "set offsets 0, 0, graph 0.1, 0\n";
  s += horizontal_line(std::max(d.fit.chi2_dof, 1e-6), "#d62728", 2);
  s += horizontal_line(1.0, "#2ca02c", 3);
  s += fmt::format(
      "set label {} at graph 0.99, first {} right offset 0,0.7 textcolor rgb "
      "'#d62728'\n",
      gnuplot_quote(fmt::format("model as given: {:.3g}", d.fit.chi2_dof)),
      gp_number(std::max(d.fit.chi2_dof, 1e-6)));
  s += "plot $c using 1:2:4:xtic(3) with boxes lc rgb variable "
       "title 'green: BIC improves, grey: not worth its parameters'\n";
  return gnuplot_svg(s, "candidates", "chi2/dof after adding each candidate term");
}

std::string allan_plot(const ReportData& r, bool gyro) { return allan_plot(*r.noise, gyro); }

std::string allan_plot(const solver::RunNoise& noise, bool gyro) {
  std::string s = svg_terminal(1000, 460);
  double ymin = std::numeric_limits<double>::infinity(), ymax = 0.0;
  double tmin = std::numeric_limits<double>::infinity(), tmax = 0.0;
  std::vector<const solver::ChannelNoise*> chans;
  for (const auto& c : noise.channels) {
    if (solver::is_gyro(c.channel) == gyro) chans.push_back(&c);
  }
  for (std::size_t k = 0; k < chans.size(); ++k) {
    std::vector<std::string> rows;
    for (const auto& p : chans[k]->allan.points) {
      if (!(p.deviation > 0.0) || !std::isfinite(p.deviation)) continue;
      const double lo = std::isfinite(p.lo) && p.lo > 0 ? p.lo : p.deviation;
      const double hi = std::isfinite(p.hi) && p.hi > 0 ? p.hi : p.deviation;
      rows.push_back(fmt::format("{} {} {} {}", gp_number(p.tau_s), gp_number(p.deviation),
                                 gp_number(lo), gp_number(hi)));
      ymin = std::min(ymin, lo);
      ymax = std::max(ymax, hi);
      tmin = std::min(tmin, p.tau_s);
      tmax = std::max(tmax, p.tau_s);
    }
    if (rows.empty()) rows.push_back("NaN NaN NaN NaN");
    s += data_block(fmt::format("m{}", k), rows);
  }
  if (!(tmax > tmin)) {
    tmin = 1.0;
    tmax = 10.0;
  }
  if (!(ymax > ymin)) {
    ymin = 1e-6;
    ymax = 1.0;
  }
  // The fitted model and its terms (IEEE 952 asymptotes) on a dense tau grid.
  const double floor = solver::flicker_floor_factor();
  for (std::size_t k = 0; k < chans.size(); ++k) {
    const solver::NoiseTerms& t = chans[k]->terms;
    const auto term = [](const solver::NoiseTerm& n, double v) {
      return n.resolved ? gp_number(v) : std::string("NaN");
    };
    std::vector<std::string> rows;
    for (int i = 0; i <= 80; ++i) {
      const double tau = tmin * std::pow(tmax / tmin, i / 80.0);
      rows.push_back(
          fmt::format("{} {} {} {} {} {} {}", gp_number(tau),
                      gp_number(std::sqrt(solver::noise_model_allan_variance(t, tau))),
                      term(t.quantization, std::sqrt(3.0) * t.quantization.value / tau),
                      term(t.random_walk, t.random_walk.value / std::sqrt(tau)),
                      term(t.bias_instability, floor * t.bias_instability.value),
                      term(t.rate_random_walk, t.rate_random_walk.value * std::sqrt(tau / 3.0)),
                      term(t.rate_ramp, t.rate_ramp.value * tau / std::sqrt(2.0))));
    }
    s += data_block(fmt::format("f{}", k), rows);
  }
  const std::string unit(gyro ? "deg/s" : "m/s^2");
  s += "set logscale xy\nset format y '%.0e'\nset key bottom left box lc rgb '#cccccc' "
       "opaque font ',11'\n";
  s += fmt::format("set xrange [{}:{}]\nset yrange [{}:{}]\n", gp_number(tmin / 1.3),
                   gp_number(tmax * 1.3), gp_number(ymin / 2.0), gp_number(ymax * 2.0));
  s +=
      fmt::format("set xlabel 'averaging time tau [s]'\nset ylabel 'Allan deviation [{}]'\n", unit);
  s += fmt::format("set title {}\n",
                   gnuplot_quote(fmt::format(
                       "{}: step {} ({}), {:.0f} s at {:.4g} Hz", gyro ? "gyro" : "accelerometer",
                       noise.step, noise.step_label, noise.duration_s, noise.sample_rate_hz)));
  constexpr std::array<const char*, 5> kTermNames = {"Q quantization", "N random walk",
                                                     "B bias instability (0.664 B)",
                                                     "K rate random walk", "R rate ramp"};
  std::array<bool, 5> titled{};
  std::string plot = "plot ";
  for (std::size_t k = 0; k < chans.size(); ++k) {
    const std::string name(solver::to_string(chans[k]->channel));
    plot += fmt::format(
        "{}$m{} using 1:2:3:4 with yerrorbars pt 7 ps 0.6 lc rgb '{}' title '{} measured', "
        "$f{} using 1:2 with lines lw 2 lc rgb '{}' title '{} fit'",
        k ? ", " : "", k, colour(k), name, k, colour(k), name);
    const solver::NoiseTerms& t = chans[k]->terms;
    const std::array<bool, 5> resolved = {t.quantization.resolved, t.random_walk.resolved,
                                          t.bias_instability.resolved, t.rate_random_walk.resolved,
                                          t.rate_ramp.resolved};
    for (std::size_t j = 0; j < 5; ++j) {
      if (!resolved[j]) continue;
      plot += fmt::format(
          ", $f{} using 1:{} with lines lw 1 dt {} lc rgb '{}' {}", k, j + 3, j + 2, colour(k),
          titled[j] ? std::string("notitle") : "title " + gnuplot_quote(kTermNames[j]));
      titled[j] = true;
    }
  }
  return gnuplot_svg(s + plot + "\n", gyro ? "allan-gyro" : "allan-accel",
                     fmt::format("Allan deviation of the {}", gyro ? "gyros" : "accelerometers"));
}

}  // namespace calstand::analysis

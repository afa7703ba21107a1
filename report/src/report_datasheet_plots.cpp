#include "report/report_datasheet_plots.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "core/units.hpp"
#include "render/gnuplot_svg.hpp"

namespace calstand::analysis {
namespace {

// One colour per axis, as the bandwidth plot draws them.
constexpr std::array<const char*, 3> kAxisColour = {"#c0392b", "#27ae60", "#2c6fbb"};
constexpr std::array<const char*, 2> kSensor = {"gyro", "accelerometer"};
constexpr std::array<const char*, 2> kUnit = {"deg/h", "ug"};

char axis_letter(std::size_t axis) { return static_cast<char>('x' + axis); }

}  // namespace

std::string repeatability_plot(const RepeatabilityAnalysis& r) {
  std::string s = svg_terminal(1000, 620);
  for (std::size_t c = 0; c < 6; ++c) {
    std::vector<std::string> rows;
    const auto& biases = r.channels[c].turn_on_bias;
    for (std::size_t k = 0; k < biases.size(); ++k) {
      rows.push_back(fmt::format("{} {}", k + 1, gp_number(biases[k])));
    }
    if (rows.empty()) rows.push_back("NaN NaN");
    s += data_block(fmt::format("c{}", c), rows);
  }
  s += "set multiplot layout 2,1\n";
  s += fmt::format("set xrange [0.5:{}]\nset xtics 1\nset xlabel 'power cycle'\n",
                   static_cast<double>(r.cycles) + 0.5);
  s += "set key outside right top\n" + horizontal_line(0.0, "#555555", 1);
  for (std::size_t sensor = 0; sensor < 2; ++sensor) {
    s += fmt::format("set ylabel 'turn-on bias [{}]'\n", kUnit[sensor]);
    s += fmt::format(
        "set title '{}: turn-on bias of each power-up less the mean over the "
        "cycles'\n",
        kSensor[sensor]);
    std::string plot = "plot ";
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const std::size_t c = sensor * 3 + axis;
      plot +=
          fmt::format("{}$c{} using 1:2 with linespoints pt 7 ps 0.8 lw 1.5 lc rgb '{}' title {}",
                      axis ? ", " : "", c, kAxisColour[axis],
                      gnuplot_quote(fmt::format("{}: 1 sigma {:.3g} {}", axis_letter(axis),
                                                r.channels[c].repeatability, kUnit[sensor])));
    }
    s += plot + "\n";
  }
  s += "unset multiplot\n";
  return gnuplot_svg(s, "repeatability-cycles", "turn-on bias of each power cycle");
}

std::string warmup_plot(const WarmupAnalysis& w, const WarmupSeries& series) {
  std::string s = svg_terminal(1000, 640);
  for (std::size_t c = 0; c < 6; ++c) {
    std::vector<std::string> rows;
    for (std::size_t i = 0; i < series.t_s.size() && i < series.deviation[c].size(); ++i) {
      rows.push_back(fmt::format(
          "{} {} {}", gp_number(series.t_s[i]), gp_number(series.deviation[c][i]),
          i < series.fitted[c].size() ? gp_number(series.fitted[c][i]) : std::string("NaN")));
    }
    if (rows.empty()) rows.push_back("NaN NaN NaN");
    s += data_block(fmt::format("d{}", c), rows);
  }
  s += "set multiplot layout 2,1\nset xlabel 'time from power-up [s]'\n";
  s += fmt::format("set xrange [0:{}]\nset key outside right top\n", gp_number(w.duration_s));
  s += horizontal_line(0.0, "#555555", 1);
  for (std::size_t sensor = 0; sensor < 2; ++sensor) {
    s += fmt::format("set ylabel 'bias less settled [{}]'\n", kUnit[sensor]);
    s += fmt::format("set title '{}: means over {:.3g} s and the fitted transient'\n",
                     kSensor[sensor], w.bin_s);
    std::string plot = "plot ";
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const std::size_t c = sensor * 3 + axis;
      const ChannelWarmup& ch = w.channels[c];
      plot += fmt::format(
          "{}$d{} using 1:2 with points pt 7 ps 0.35 lc rgb '{}' title {}", axis ? ", " : "", c,
          kAxisColour[axis],
          gnuplot_quote(ch.resolved ? fmt::format("{}", axis_letter(axis))
                                    : fmt::format("{}: no transient resolved", axis_letter(axis))));
      if (!series.fitted[c].empty()) {
        plot += fmt::format(", $d{} using 1:3 with lines lw 2.5 lc rgb '{}' title {}", c,
                            kAxisColour[axis],
                            gnuplot_quote(fmt::format(
                                "{} fit: tau {:.3g} s{}", axis_letter(axis), ch.time_constant_s,
                                ch.temperature_term ? " + temperature" : "")));
      }
    }
    s += plot + "\n";
  }
  s += "unset multiplot\n";
  return gnuplot_svg(s, "warmup-transient", "the bias after power-up and its fitted transient");
}

std::string hysteresis_plot(const HysteresisAnalysis& h) {
  // Bias parameters only (the scale factors are in the table): deg/s and m/s^2 to deg/h, ug.
  // The difference, not the two legs: the axes' biases lie far apart, their hysteresis is small.
  constexpr std::array<const char*, 2> kParameter = {"gyro_bias.", "accel_bias."};
  constexpr std::array<double, 2> kToDatasheet = {3600.0, 1.0 / core::kMicroGToMps2};
  // Points of the three axes side by side at each set point, a fraction of the steps apart.
  double spacing_c = 0.0;
  for (std::size_t i = 1; i < h.points.size(); ++i) {
    const double d = std::abs(h.points[i].temperature_c - h.points[i - 1].temperature_c);
    if (d > 0.0 && (spacing_c == 0.0 || d < spacing_c)) spacing_c = d;
  }
  const double offset_c = spacing_c > 0.0 ? 0.04 * spacing_c : 0.5;
  std::string s = svg_terminal(1000, 640);
  for (std::size_t sensor = 0; sensor < 2; ++sensor) {
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const std::string name = kParameter[sensor] + std::string(1, axis_letter(axis));
      std::vector<std::string> rows;
      for (const HysteresisPoint& p : h.points) {
        if (p.parameter != name) continue;
        const double k = kToDatasheet[sensor];
        const double t = p.temperature_c + (static_cast<double>(axis) - 1.0) * offset_c;
        rows.push_back(fmt::format("{} {} {}", gp_number(t), gp_number(k * p.difference),
                                   gp_number(k * p.difference_sigma)));
      }
      if (rows.empty()) rows.push_back("NaN NaN NaN");
      s += data_block(fmt::format("h{}{}", sensor, axis), rows);
    }
  }
  s += "set multiplot layout 2,1\nset xlabel 'set point [degC]'\n";
  s += "set offsets graph 0.08, graph 0.08, graph 0.1, graph 0.1\nset key outside right top\n";
  s += horizontal_line(0.0, "#555555", 1);
  for (std::size_t sensor = 0; sensor < 2; ++sensor) {
    s += fmt::format("set ylabel 'up - down [{}]'\n", kUnit[sensor]);
    s += fmt::format(
        "set title '{} bias: up minus down at each set point, 1 sigma (0: no hysteresis)'\n",
        kSensor[sensor]);
    std::string plot = "plot ";
    for (std::size_t axis = 0; axis < 3; ++axis) {
      plot += fmt::format(
          "{}$h{}{} using 1:2:3 with yerrorbars pt 7 ps 0.9 lw 1.5 lc rgb '{}' title '{}'",
          axis ? ", " : "", sensor, axis, kAxisColour[axis], axis_letter(axis));
    }
    s += plot + "\n";
  }
  s += "unset multiplot\n";
  return gnuplot_svg(s, "hysteresis-difference", "bias up minus down at each set point");
}

}  // namespace calstand::analysis

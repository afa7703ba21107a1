#include "analysis/report_datasheet_plots.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "analysis/gnuplot_svg.hpp"
#include "core/units.hpp"

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
    s += fmt::format("set title '{}: turn-on bias of each power-up less the mean over the "
                     "cycles'\n",
                     kSensor[sensor]);
    std::string plot = "plot ";
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const std::size_t c = sensor * 3 + axis;
      plot += fmt::format(
          "{}$c{} using 1:2 with linespoints pt 7 ps 0.8 lw 1.5 lc rgb '{}' title {}",
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
  constexpr int kCurvePoints = 200;
  for (std::size_t c = 0; c < 6; ++c) {
    std::vector<std::string> rows;
    for (std::size_t i = 0; i < series.t_s.size() && i < series.deviation[c].size(); ++i) {
      rows.push_back(gp_number(series.t_s[i]) + " " + gp_number(series.deviation[c][i]));
    }
    if (rows.empty()) rows.push_back("NaN NaN");
    s += data_block(fmt::format("d{}", c), rows);
    const ChannelWarmup& ch = w.channels[c];
    std::vector<std::string> curve;
    for (int i = 0; i <= kCurvePoints; ++i) {
      const double t = w.duration_s * i / kCurvePoints;
      const double v =
          ch.time_constant_s > 0.0 ? ch.amplitude * std::exp(-t / ch.time_constant_s) : 0.0;
      curve.push_back(gp_number(t) + " " + gp_number(v));
    }
    s += data_block(fmt::format("f{}", c), curve);
  }
  s += "set multiplot layout 2,1\nset xlabel 'time from power-up [s]'\n";
  s += fmt::format("set xrange [0:{}]\nset key outside right top\n", gp_number(w.duration_s));
  s += horizontal_line(0.0, "#555555", 1);
  for (std::size_t sensor = 0; sensor < 2; ++sensor) {
    s += fmt::format("set ylabel 'bias less settled [{}]'\n", kUnit[sensor]);
    s += fmt::format("set title '{}: bin means ({:.3g} s) and the fitted transient A "
                     "exp(-t/tau)'\n",
                     kSensor[sensor], w.bin_s);
    std::string plot = "plot ";
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const std::size_t c = sensor * 3 + axis;
      const ChannelWarmup& ch = w.channels[c];
      plot += fmt::format(
          "{}$d{} using 1:2 with points pt 7 ps 0.35 lc rgb '{}' title '{} data', "
          "$f{} using 1:2 with lines lw 2.5 dt {} lc rgb '{}' title {}",
          axis ? ", " : "", c, kAxisColour[axis], axis_letter(axis), c, ch.resolved ? 1 : 2,
          kAxisColour[axis],
          gnuplot_quote(ch.resolved
                            ? fmt::format("{}: tau {:.3g} s", axis_letter(axis), ch.time_constant_s)
                            : fmt::format("{}: no transient", axis_letter(axis))));
    }
    s += plot + "\n";
  }
  s += "unset multiplot\n";
  return gnuplot_svg(s, "warmup-transient", "the bias after power-up and its fitted transient");
}

std::string hysteresis_plot(const HysteresisAnalysis& h) {
  // Bias parameters only (the scale factors are in the table): deg/s and m/s^2 to deg/h, ug.
  constexpr std::array<const char*, 2> kParameter = {"gyro_bias.", "accel_bias."};
  constexpr std::array<double, 2> kToDatasheet = {3600.0, 1.0 / core::kMicroGToMps2};
  std::string s = svg_terminal(1000, 640);
  for (std::size_t sensor = 0; sensor < 2; ++sensor) {
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const std::string name = kParameter[sensor] + std::string(1, axis_letter(axis));
      std::vector<std::string> rows;
      for (const HysteresisPoint& p : h.points) {
        if (p.parameter != name) continue;
        const double k = kToDatasheet[sensor];
        rows.push_back(fmt::format("{} {} {} {} {}", gp_number(p.temperature_c),
                                   gp_number(k * p.up), gp_number(k * p.up_sigma),
                                   gp_number(k * p.down), gp_number(k * p.down_sigma)));
      }
      if (rows.empty()) rows.push_back("NaN NaN NaN NaN NaN");
      s += data_block(fmt::format("h{}{}", sensor, axis), rows);
    }
  }
  s += "set multiplot layout 2,1\nset xlabel 'set point [degC]'\n";
  s += "set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05\nset key outside right top\n";
  for (std::size_t sensor = 0; sensor < 2; ++sensor) {
    s += fmt::format("set ylabel 'bias [{}]'\n", kUnit[sensor]);
    s += fmt::format(
        "set title '{} bias on the way up (solid, triangle up) and down (dashed, triangle "
        "down), 1 sigma'\n",
        kSensor[sensor]);
    std::string plot = "plot ";
    for (std::size_t axis = 0; axis < 3; ++axis) {
      plot += fmt::format(
          "{0}$h{1}{2} using 1:2:3 with yerrorlines pt 9 ps 0.9 lw 1.5 lc rgb '{3}' title "
          "'{4} up', $h{1}{2} using 1:4:5 with yerrorlines pt 11 ps 0.9 lw 1.5 dt 2 lc rgb '{3}' "
          "title '{4} down'",
          axis ? ", " : "", sensor, axis, kAxisColour[axis], axis_letter(axis));
    }
    s += plot + "\n";
  }
  s += "unset multiplot\n";
  return gnuplot_svg(s, "hysteresis-legs", "biases up and down the temperature staircase");
}

}  // namespace calstand::analysis

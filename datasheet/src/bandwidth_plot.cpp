// The gain curves of a bandwidth analysis as an SVG plot (gnuplot).
#include <fmt/format.h>

#include <array>

#include "datasheet/bandwidth.hpp"
#include "render/gnuplot_svg.hpp"

namespace calstand::analysis {

std::string bandwidth_svg(const BandwidthAnalysis& b) {
  constexpr std::array<const char*, 3> kColour = {"#c0392b", "#27ae60", "#2c6fbb"};
  std::string s = svg_terminal(700, 360);
  std::string plot;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<std::string> rows;
    for (const auto& p : b.points) {
      if (p.axis == axis) rows.push_back(gp_number(p.frequency_hz) + " " + gp_number(p.gain_db));
    }
    if (rows.empty()) continue;
    const std::string name = fmt::format("g{}", axis);
    s += data_block(name, rows);
    const auto& fc = b.bandwidth_hz[static_cast<std::size_t>(axis)];
    const std::string title =
        fc ? fmt::format("{}: -3 dB at {:.3g} Hz", static_cast<char>('x' + axis), *fc)
           : fmt::format("{}: no -3 dB crossing", static_cast<char>('x' + axis));
    plot += fmt::format("{}${} using 1:2 with linespoints pt 7 ps 0.6 lc rgb '{}' title {}",
                        plot.empty() ? "plot " : ", ", name,
                        kColour[static_cast<std::size_t>(axis)], gnuplot_quote(title));
  }
  s += "set logscale x\nset xlabel 'frequency [Hz]'\nset ylabel 'gain [dB]'\n";
  s += "set key outside bottom center horizontal\n";
  s += horizontal_line(-3.0103, "#888888", 2);
  s += plot + "\n";
  return gnuplot_svg(s, "bandwidth-gain", "gyro gain against the table encoder");
}

}  // namespace calstand::analysis

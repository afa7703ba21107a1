#include <fmt/format.h>

#include <array>
#include <cmath>

#include "factory/certificate.hpp"
#include "render/gnuplot_svg.hpp"

namespace calstand::analysis {

// What a person checks on a certificate: every step's residual within a few step-noise sigmas,
// i.e. the calibrated model leaves nothing but noise. One panel per sensor, axes by colour.
std::string certificate_residual_plot(const std::vector<solver::StepResidual>& steps) {
  constexpr std::array<const char*, 3> kAxisColour = {"#1f77b4", "#2ca02c", "#d62728"};
  constexpr std::array<double, 3> kOffset = {-0.2, 0.0, 0.2};
  std::string s = svg_terminal(900, 250);
  double max_index = 0.0;
  for (int sensor = 0; sensor < 2; ++sensor) {
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<std::string> rows;
      for (const solver::StepResidual& st : steps) {
        max_index = std::max(max_index, static_cast<double>(st.index));
        const double z = st.z()[sensor * 3 + axis];
        if (std::isfinite(z)) {
          rows.push_back(
              fmt::format("{} {}", static_cast<double>(st.index) + kOffset[axis], gp_number(z)));
        }
      }
      if (rows.empty()) rows.push_back("NaN NaN");
      s += data_block(fmt::format("s{}a{}", sensor, axis), rows);
    }
  }
  s += "set multiplot layout 1,2\n";
  s += fmt::format("set xrange [-0.5:{}]\nset xlabel 'step'\n", max_index + 0.5);
  s += "set yrange [*<-3:3<*]\nset key outside bottom center horizontal\n";
  s += horizontal_line(0.0, "#555555", 1) + horizontal_line(2.0, "#999999", 3) +
       horizontal_line(-2.0, "#999999", 3);
  for (int sensor = 0; sensor < 2; ++sensor) {
    s += fmt::format("set title '{} residual / step noise'\nset ylabel 'z'\n",
                     sensor == 0 ? "gyro" : "accelerometer");
    std::string plot = "plot ";
    for (int axis = 0; axis < 3; ++axis) {
      plot += fmt::format("{}$s{}a{} using 1:2 with points pt 7 ps 0.6 lc rgb '{}' title '{}'",
                          axis ? ", " : "", sensor, axis, kAxisColour[axis], "xyz"[axis]);
    }
    s += plot + "\n";
  }
  s += "unset multiplot\n";
  return gnuplot_svg(s, "certificate-residuals", "step residuals against the step noise");
}

}  // namespace calstand::analysis

// calstand units: converts the mixed units of inertial sensor datasheets (deg/sqrt(h),
// ug/sqrt(Hz), deg/h/sqrt(h), mGal, ppm, ...) so a spec sheet can be checked against results.
#include <fmt/format.h>

#include <array>
#include <charconv>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <system_error>

#include "commands.hpp"
#include "core/units.hpp"

namespace calstand::cli {
namespace {

struct UnitsOptions {
  std::string quantity;
  std::string to;
  bool json = false;
};

// Scale factors such as pi/180/60 leave last-bit noise (0.0025000000000000005); 15 significant
// digits drop it while keeping more precision than any datasheet figure carries. to_chars and
// from_chars take subnormals such as 1e-310 (std::stod throws on them) and ignore the locale.
double without_rounding_noise(double v) {
  std::array<char, 64> text{};
  const auto written =
      std::to_chars(text.data(), text.data() + text.size(), v, std::chars_format::general, 15);
  if (written.ec != std::errc()) return v;
  double rounded = v;
  const auto read = std::from_chars(text.data(), written.ptr, rounded);
  return read.ec == std::errc() ? rounded : v;
}

void run_units(const UnitsOptions& options, bool has_target) {
  const core::Quantity q = core::parse_quantity(options.quantity);
  // Without --to the target is the coherent SI unit, so the value shows what the solver sees.
  const std::string target = has_target ? options.to : core::si_unit(q.unit);
  const double result =
      has_target ? core::convert(q.value, q.unit_text, target) : q.value * q.unit.scale;

  if (options.json) {
    nlohmann::ordered_json j;
    j["value"] = q.value;
    j["from"] = q.unit_text;
    j["to"] = target;
    j["result"] = without_rounding_noise(result);
    if (!has_target) j["dimension"] = core::describe_dimension(q.unit);
    std::cout << j.dump() << "\n";
    return;
  }
  const auto with_unit = [](double v, const std::string& unit) {
    return unit.empty() ? fmt::format("{:.10g}", v) : fmt::format("{:.10g} {}", v, unit);
  };
  std::cout << with_unit(q.value, q.unit_text) << " = " << with_unit(result, target);
  if (!has_target) std::cout << " [" << core::describe_dimension(q.unit) << "]";
  std::cout << "\n";
}

}  // namespace

void register_units(CLI::App& app) {
  auto options = std::make_shared<UnitsOptions>();
  CLI::App* cmd = app.add_subcommand(
      "units", "Convert a datasheet quantity, e.g. \"0.15 deg/sqrt(h)\" --to \"deg/s/sqrt(Hz)\"");
  cmd->add_option("quantity", options->quantity,
                  "number and unit: rad deg arcsec, s h Hz, m, g mg ug (gravity), mGal, ppm %; "
                  "* / ^ ( ) sqrt()")
      ->required();
  CLI::Option* to = cmd->add_option(
      "--to", options->to, "target unit, same dimension (\"\" for a plain number); default: SI");
  cmd->add_flag("--json", options->json, "print {value, from, to, result} as one JSON line");
  cmd->callback([options, to] { run_units(*options, to->count() > 0); });
}

}  // namespace calstand::cli

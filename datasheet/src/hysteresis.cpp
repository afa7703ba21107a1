#include "datasheet/hysteresis.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <utility>

#include "analysis/run_model.hpp"
#include "core/error.hpp"
#include "solver/model.hpp"
#include "solver/noise_estimate.hpp"

namespace calstand::analysis {
namespace {

using Leg = std::pair<std::string, double>;  ///< ("up" | "down", set point)

// The steps of each leg and set point, by their loop values.
std::map<Leg, solver::RunData> split_by_leg(const solver::RunData& data) {
  std::map<Leg, solver::RunData> out;
  for (const store::StepData& step : data.steps) {
    const nlohmann::json loops = step.step.commanded.value("loop_values", nlohmann::json::object());
    if (!loops.contains("leg") || !loops.contains("temperature") ||
        !loops["temperature"].is_number()) {
      continue;
    }
    const Leg key{loops["leg"].get<std::string>(), loops["temperature"].get<double>()};
    auto [it, added] = out.try_emplace(key);
    if (added) it->second.setup = data.setup;
    it->second.steps.push_back(step);
  }
  return out;
}

}  // namespace

HysteresisAnalysis analyse_hysteresis(store::Database& db, std::int64_t run,
                                      const std::string& device) {
  const solver::RunData data = load_fit_data(db, run, device);
  const solver::Model model = solver::Model::parse(kHysteresisModel);
  const std::map<Leg, solver::RunData> legs = split_by_leg(data);
  std::map<Leg, solver::FitResult> fits;
  for (const auto& [leg, subset] : legs) fits.emplace(leg, solver::fit_run(subset, model));
  HysteresisAnalysis out;
  out.run = run;
  out.device = data.setup.device;
  out.model = model.text();
  for (const auto& [leg, fit] : fits) {
    const auto& [direction, temperature] = leg;
    const std::string other = direction == "up" ? "down" : "up";
    if (fits.count({other, temperature}) == 0) {
      (direction == "up" ? out.up_only_c : out.down_only_c).push_back(temperature);
      continue;
    }
    if (direction != "up") continue;  // each pair once, from its up leg
    const solver::FitResult& down = fits.at({"down", temperature});
    for (const solver::FittedParameter& u : fit.parameters) {
      for (const solver::FittedParameter& d : down.parameters) {
        if (d.name != u.name) continue;
        HysteresisPoint p;
        p.temperature_c = temperature;
        p.parameter = u.name;
        p.unit = u.unit;
        p.up = u.value;
        p.up_sigma = u.sigma;
        p.down = d.value;
        p.down_sigma = d.sigma;
        p.difference = u.value - d.value;
        p.difference_sigma = std::hypot(u.sigma, d.sigma);
        p.z = p.difference_sigma > 0.0 ? p.difference / p.difference_sigma : 0.0;
        out.points.push_back(p);
      }
    }
  }
  if (out.points.empty()) {
    throw core::InputError(fmt::format("run {}", run),
                           "has no set point measured on both the way up and the way down "
                           "(steps with loop values leg and temperature: library procedure "
                           "thermal-hysteresis)");
  }
  return out;
}

nlohmann::json to_json(const HysteresisAnalysis& h) {
  nlohmann::json points = nlohmann::json::array();
  for (const HysteresisPoint& p : h.points) {
    points.push_back({{"temperature_c", p.temperature_c},
                      {"parameter", p.parameter},
                      {"unit", p.unit},
                      {"up", p.up},
                      {"up_sigma", p.up_sigma},
                      {"down", p.down},
                      {"down_sigma", p.down_sigma},
                      {"difference", p.difference},
                      {"difference_sigma", p.difference_sigma},
                      {"z", p.z}});
  }
  return {{"run", h.run},     {"device", h.device},       {"model", h.model},
          {"points", points}, {"up_only_c", h.up_only_c}, {"down_only_c", h.down_only_c}};
}

}  // namespace calstand::analysis

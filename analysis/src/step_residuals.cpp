#include "analysis/step_residuals.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace calstand::analysis {
namespace {

nlohmann::json six(const solver::Vector6d& v) {
  nlohmann::json out = nlohmann::json::array();
  for (Eigen::Index i = 0; i < 6; ++i) {
    // JSON has no NaN: a channel the fit left out is null.
    out.push_back(std::isfinite(v(i)) ? nlohmann::json(v(i)) : nlohmann::json());
  }
  return out;
}

solver::Vector6d six_from(const nlohmann::json& a, const std::string& where) {
  if (!a.is_array() || a.size() != 6) {
    throw core::InputError(where, "expected an array of 6 numbers or nulls");
  }
  solver::Vector6d v;
  for (std::size_t i = 0; i < 6; ++i) {
    if (a[i].is_null()) {
      v(static_cast<Eigen::Index>(i)) = std::numeric_limits<double>::quiet_NaN();
    } else if (a[i].is_number()) {
      v(static_cast<Eigen::Index>(i)) = a[i].get<double>();
    } else {
      throw core::InputError(fmt::format("{}[{}]", where, i), "expected a number or null");
    }
  }
  return v;
}

}  // namespace

nlohmann::json step_residuals_json(const solver::FitResult& fit) {
  nlohmann::json steps = nlohmann::json::array();
  for (const solver::StepResidual& s : fit.steps) {
    steps.push_back({{"index", s.index},
                     {"label", s.label},
                     {"residual", six(s.residual)},
                     {"sigma", six(s.sigma)}});
  }
  return {{"format", kStepResidualsFormat}, {"steps", steps}};
}

std::vector<solver::StepResidual> step_residuals_from_json(const nlohmann::json& doc,
                                                           const std::string& where) {
  if (!doc.is_object() || doc.value("format", "") != kStepResidualsFormat) {
    throw core::InputError(where + ": format", fmt::format("expected {}", kStepResidualsFormat));
  }
  const nlohmann::json steps = doc.value("steps", nlohmann::json());
  if (!steps.is_array()) throw core::InputError(where + ": steps", "expected an array");
  std::vector<solver::StepResidual> out;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const std::string at = fmt::format("{}: steps[{}]", where, k);
    const nlohmann::json& s = steps[k];
    if (!s.is_object() || !s.contains("index") || !s["index"].is_number_unsigned()) {
      throw core::InputError(at + ".index", "expected a step index (an integer >= 0)");
    }
    solver::StepResidual r;
    r.index = s["index"].get<std::size_t>();
    r.label = s.value("label", "");
    r.residual = six_from(s.value("residual", nlohmann::json()), at + ".residual");
    r.sigma = six_from(s.value("sigma", nlohmann::json()), at + ".sigma");
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace calstand::analysis

// Per-plateau thermal calibration: fit_model() on each temperature plateau, then a polynomial
// in dT per parameter through the plateau values (thermal.hpp names the coefficients).

#include "solver/thermal_fit.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "core/error.hpp"

namespace calstand::solver {
namespace {

constexpr const char* kWhere = "fit_per_plateau";

/// Step indices per plateau, ascending temperature: step mean temperatures split at gaps over
/// kPlateauGapC, the clustering temperature_plateaus() uses. Assigning each step to the nearest
/// plateau mean instead would misplace steps at the edge of a wide plateau (a ramp).
std::vector<std::vector<std::size_t>> group_by_plateau(const std::vector<StepSummary>& steps) {
  std::vector<std::size_t> order(steps.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return steps[a].signals[0] < steps[b].signals[0];
  });
  std::vector<std::vector<std::size_t>> groups;
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (k == 0 || steps[order[k]].signals[0] - steps[order[k - 1]].signals[0] > kPlateauGapC) {
      groups.emplace_back();
    }
    groups.back().push_back(order[k]);
  }
  return groups;
}

enum class Kind { kBias, kScale, kConstant };

/// How a parameter varies with temperature in the contract: `<s>_bias.<a>` has the polynomial
/// `<s>_temp_bias`, `<s>_scale.<a>` the linear `<s>_temp_scale`, nothing else has a term.
Kind kind_of(const std::string& name) {
  for (const char* sensor : {"gyro", "accel"}) {
    for (const char* axis : {"x", "y", "z"}) {
      if (name == fmt::format("{}_bias.{}", sensor, axis)) return Kind::kBias;
      if (name == fmt::format("{}_scale.{}", sensor, axis)) return Kind::kScale;
    }
  }
  return Kind::kConstant;
}

const FittedParameter* find_parameter(const PlateauFit& plateau, const std::string& name) {
  for (const FittedParameter& p : plateau.parameters) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

std::string temperatures_text(const std::vector<PlateauFit>& plateaus) {
  std::vector<std::string> t;
  for (const PlateauFit& p : plateaus) t.push_back(fmt::format("{:.1f}", p.temperature_c));
  return fmt::format("{}", fmt::join(t, ", "));
}

void check_model(const Model& model) {
  for (const ModelTerm& term : model.terms()) {
    if (!term.info) continue;
    const std::string_view n = term.info->name;
    if (n.find("_temp_") != std::string_view::npos) {
      throw core::InputError(kWhere, fmt::format("the per-plateau model holds the temperature term "
                                                 "{}: one plateau cannot determine it; leave it "
                                                 "out, the polynomial across plateaus gives it",
                                                 term.name));
    }
  }
}

/// fit_model() on one plateau, its errors naming the plateau.
PlateauFit fit_plateau(const std::vector<StepSummary>& all, const std::vector<std::size_t>& members,
                       double temperature_c, const Model& model, const StepNoise& noise,
                       const FitOptions& options) {
  std::vector<StepSummary> steps;
  steps.reserve(members.size());
  for (std::size_t i : members) steps.push_back(all[i]);
  FitResult fit;
  try {
    fit = fit_model(steps, model, noise, options);
  } catch (const core::InputError& e) {
    throw core::InputError(kWhere, fmt::format("the plateau at {:.1f} degC has too few steps ({}) "
                                               "for the model: {}",
                                               temperature_c, members.size(), e.what()));
  }
  PlateauFit out;
  out.temperature_c = temperature_c;
  out.steps = members.size();
  out.parameters = std::move(fit.parameters);
  out.unidentifiable = std::move(fit.unidentifiable);
  out.chi2_dof = fit.chi2_dof;
  out.dof = fit.dof;
  return out;
}

}  // namespace

ThermalFitResult fit_per_plateau(const std::vector<StepSummary>& steps, const Model& model,
                                 int order, const StepNoise& noise,
                                 const ThermalFitOptions& options) {
  if (order < 1) {
    throw core::InputError(kWhere, fmt::format("order {} must be >= 1 (a thermal calibration "
                                               "fits at least a linear temperature term)",
                                               order));
  }
  check_model(model);
  const std::vector<double> temperatures = temperature_plateaus(steps);
  const std::vector<std::vector<std::size_t>> groups = group_by_plateau(steps);
  if (groups.size() != temperatures.size()) {
    throw std::logic_error(
        "fit_per_plateau: plateau grouping disagrees with temperature_plateaus()");
  }

  ThermalFitResult result;
  result.model = model.text();
  result.order = order;
  result.temperature_ref_c = options.temperature_ref_c;
  // Order first: no use fitting the plateaus when the polynomial cannot be formed.
  if (static_cast<std::size_t>(order) >= groups.size()) {
    std::vector<std::string> t;
    for (double temp : temperatures) t.push_back(fmt::format("{:.1f}", temp));
    throw core::InputError(kWhere,
                           fmt::format("order {} needs at least {} temperature plateaus, "
                                       "the run has {} (at {} degC)",
                                       order, order + 1, groups.size(), fmt::join(t, ", ")));
  }
  for (std::size_t g = 0; g < groups.size(); ++g) {
    result.plateaus.push_back(
        fit_plateau(steps, groups[g], temperatures[g], model, noise, options.fit));
  }

  ThermalOptions thermal;
  thermal.temperature_ref_c = options.temperature_ref_c;
  thermal.scale_by_chi2 = options.scale_by_chi2;
  for (const ParameterInfo& info : model.parameters()) {
    std::vector<ThermalPlateau> plateaus;
    std::vector<ThermalPoint> points;
    std::vector<std::string> missing;
    for (const PlateauFit& pf : result.plateaus) {
      const FittedParameter* p = find_parameter(pf, info.name);
      if (!p) {
        missing.push_back(fmt::format("{:.1f}", pf.temperature_c));
        continue;
      }
      plateaus.push_back({pf.temperature_c, {{p->name, p->value, p->sigma, p->unit}}});
      points.push_back({pf.temperature_c, p->value, p->sigma});
    }
    if (!missing.empty()) {
      result.skipped.push_back(
          {info.name,
           fmt::format("not identified on the plateau(s) at {} degC", fmt::join(missing, ", "))});
      continue;
    }
    const Kind kind = kind_of(info.name);
    // The contract's temperature scale term is linear, whatever the bias order.
    const int k = kind == Kind::kBias ? order : (kind == Kind::kScale ? 1 : 0);
    try {
      result.polynomials.push_back({info.name, info.unit, thermal_polynomial(points, k, thermal)});
      if (kind == Kind::kConstant) {
        const ThermalPolynomial& mean = result.polynomials.back().polynomial;
        result.constants.push_back({info.name, mean.coefficients(0), mean.sigmas(0), info.unit});
      } else {
        for (ClassicalEstimate& e : thermal_calibration(plateaus, k, thermal)) {
          result.coefficients.push_back(std::move(e));
        }
      }
    } catch (const core::InputError& e) {
      throw core::InputError(kWhere, fmt::format("{} over plateaus at {} degC: {}", info.name,
                                                 temperatures_text(result.plateaus), e.what()));
    }
  }
  return result;
}

nlohmann::json thermal_fit_to_json(const ThermalFitResult& result) {
  const auto estimates = [](const std::vector<ClassicalEstimate>& list) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& e : list) {
      a.push_back({{"name", e.name}, {"value", e.value}, {"sigma", e.sigma}, {"unit", e.unit}});
    }
    return a;
  };
  nlohmann::json j;
  j["model"] = result.model;
  j["order"] = result.order;
  j["temperature_ref_c"] = result.temperature_ref_c;
  j["plateaus"] = nlohmann::json::array();
  for (const PlateauFit& p : result.plateaus) {
    nlohmann::json params = nlohmann::json::array();
    for (const auto& f : p.parameters) {
      params.push_back(
          {{"name", f.name}, {"value", f.value}, {"sigma", f.sigma}, {"unit", f.unit}});
    }
    nlohmann::json unid = nlohmann::json::array();
    for (const auto& u : p.unidentifiable) unid.push_back({{"name", u.name}, {"reason", u.reason}});
    j["plateaus"].push_back({{"temperature_c", p.temperature_c},
                             {"steps", p.steps},
                             {"chi2_dof", p.chi2_dof},
                             {"dof", p.dof},
                             {"parameters", std::move(params)},
                             {"unidentifiable", std::move(unid)}});
  }
  j["coefficients"] = estimates(result.coefficients);
  j["constants"] = estimates(result.constants);
  j["polynomials"] = nlohmann::json::array();
  for (const ParameterPolynomial& p : result.polynomials) {
    const Eigen::VectorXd& r = p.polynomial.residuals;
    j["polynomials"].push_back({{"parameter", p.parameter},
                                {"unit", p.unit},
                                {"order", p.polynomial.order},
                                {"chi2_dof", p.polynomial.chi2_dof},
                                {"dof", p.polynomial.dof},
                                {"residuals", std::vector<double>(r.data(), r.data() + r.size())}});
  }
  j["skipped"] = nlohmann::json::array();
  for (const ThermalSkip& s : result.skipped)
    j["skipped"].push_back({{"name", s.name}, {"reason", s.reason}});
  return j;
}

}  // namespace calstand::solver

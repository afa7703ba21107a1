#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solver/classical.hpp"
#include "solver/fit.hpp"
#include "solver/model.hpp"
#include "solver/step_summary.hpp"
#include "solver/thermal.hpp"

/// Per-plateau thermal calibration (issue 4: "per-plateau fits and a polynomial of the chosen
/// order in temperature"): the general fit runs on each temperature plateau of a run on its
/// own, then each parameter's plateau estimates are fitted by a weighted polynomial in
/// dT = T - T_ref (thermal.hpp). Complements a single fit with `*_temp_bias:N` terms: the
/// plateau tables show whether the temperature dependence really is a low-order polynomial
/// and which parameters move with temperature at all.
namespace calstand::solver {

/// Options of fit_per_plateau().
struct ThermalFitOptions {
  /// T_ref of dT [degC]: pass the run's RunSetup::temperature_ref_c (contract default 25).
  double temperature_ref_c = 25.0;
  /// Options of each plateau's fit_model() (rows, collinearity limits, chi2 inflation).
  FitOptions fit;
  /// Passed to thermal_polynomial(): scale the polynomial covariance by its chi2/dof.
  bool scale_by_chi2 = false;
};

/// One plateau's general fit.
struct PlateauFit {
  double temperature_c = 0.0;                  ///< mean of the plateau's step temperatures [degC]
  std::size_t steps = 0;                       ///< steps on the plateau
  std::vector<FittedParameter> parameters;     ///< identified on this plateau, model order
  std::vector<Unidentifiable> unidentifiable;  ///< as fit_model() reports them
  double chi2_dof = 0.0;
  int dof = 0;
};

/// One parameter's polynomial through its plateau values (diagnostics: residuals, chi2/dof).
struct ParameterPolynomial {
  std::string parameter;  ///< plateau parameter, e.g. "gyro_bias.x"
  std::string unit;       ///< its contract unit
  ThermalPolynomial polynomial;
};

/// A parameter for which no temperature model was formed, and why.
struct ThermalSkip {
  std::string name;
  std::string reason;  ///< one sentence
};

/// Result of fit_per_plateau().
struct ThermalFitResult {
  std::string model;  ///< Model::text() of the per-plateau model
  int order = 1;      ///< bias polynomial order N
  double temperature_ref_c = 25.0;
  std::vector<PlateauFit> plateaus;  ///< ascending temperature
  /// Contract-named coefficients: `<s>_bias.<a>` (value at T_ref) and `<s>_temp_bias.<a>1..N`
  /// [unit/degC^k] for biases; `<s>_scale.<a>` [ppm] and `<s>_temp_scale.<a>` [ppm/degC] for
  /// scale factors (always linear: the contract has only a linear temperature scale term).
  std::vector<ClassicalEstimate> coefficients;
  /// Parameters with no temperature term in the contract (misalignment, g-sensitivity,
  /// custom terms, ...): their weighted mean over the plateaus, with its sigma.
  std::vector<ClassicalEstimate> constants;
  /// Every polynomial behind `coefficients` and `constants` (order 0 for constants).
  std::vector<ParameterPolynomial> polynomials;
  /// Parameters not identified on every plateau: no temperature model for them.
  std::vector<ThermalSkip> skipped;
};

/// Fits `model` on each temperature plateau of `steps` (plateaus as temperature_plateaus()
/// forms them: step mean temperatures split at gaps over 2 degC) with fit_model() and the
/// shared noise model `noise` (white, or with a wandering bias), then fits each parameter
/// identified on every plateau against dT = T - options.temperature_ref_c: biases by a polynomial
/// of `order`, scale factors linearly, everything else by its weighted mean (see ThermalFitResult).
///
/// Throws core::InputError (where() = "fit_per_plateau") when order < 1; when the run has
/// fewer than order + 1 plateaus (message e.g. "order 2 needs at least 3 temperature
/// plateaus, the run has 2 (at 10.0, 40.0 degC)"); when `model` holds a temperature term
/// (`*_temp_bias`, `*_temp_scale`: one plateau cannot determine them, the polynomial does);
/// when a plateau has too few steps for `model` (message names the plateau's temperature and
/// step count); or when a polynomial fit fails.
ThermalFitResult fit_per_plateau(const std::vector<StepSummary>& steps, const Model& model,
                                 int order, const StepNoise& noise,
                                 const ThermalFitOptions& options = {});

/// The same with white noise alone.
inline ThermalFitResult fit_per_plateau(const std::vector<StepSummary>& steps, const Model& model,
                                        int order, const NoiseFloor& floor,
                                        const ThermalFitOptions& options = {}) {
  return fit_per_plateau(steps, model, order,
                         StepNoise::white_only(floor, "white noise only, as asked"), options);
}

/// The result as a JSON document: {"model", "order", "temperature_ref_c", "plateaus": [{
/// "temperature_c", "steps", "chi2_dof", "dof", "parameters": [{name, value, sigma, unit}],
/// "unidentifiable": [{name, reason}]}], "coefficients": [{name, value, sigma, unit}],
/// "constants": [...], "polynomials": [{"parameter", "unit", "order", "chi2_dof", "dof",
/// "residuals": [per plateau]}], "skipped": [{name, reason}]}.
nlohmann::json thermal_fit_to_json(const ThermalFitResult& result);

}  // namespace calstand::solver

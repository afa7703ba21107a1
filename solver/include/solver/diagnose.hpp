#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solver/fit.hpp"
#include "solver/groups.hpp"

namespace calstand::solver {

/// One catalogue term tried on top of the model.
struct Candidate {
  std::string term;             ///< e.g. "gyro_g_sensitivity", "gyro_temp_bias:2"
  double delta_bic = 0.0;       ///< BIC after - before (chi2 + k ln n); negative is better
  double p_value = 1.0;         ///< F-test of the added parameters
  double chi2_dof_after = 0.0;
  int added_parameters = 0;     ///< identified parameters the term adds
  std::string explanation;      ///< the physical effect and which steps it fixes, in words
};

/// How strongly a channel's step residuals (z-scores) follow a signal.
struct SignalCorrelation {
  std::string signal;   ///< "temperature_rate", "rate_x^2", "abs(force_z)"
  std::string channel;  ///< gx .. az
  double correlation = 0.0;  ///< Pearson, over steps
};

struct Diagnosis {
  FitResult fit;                        ///< the model as given
  std::vector<GroupQuality> groups;     ///< of `fit`, worst first
  std::vector<Candidate> candidates;    ///< best (most negative delta_bic) first
  std::vector<std::string> untestable;  ///< candidate terms the run cannot determine at all
  std::vector<SignalCorrelation> signals;  ///< strongest first
  bool explained = false;  ///< the model, or the model with the best candidate, fits the noise
  std::string advice;      ///< one paragraph for the user
  /// The term to add: the best candidate when the model is above the noise floor and that
  /// candidate explains (all or most of) the excess; empty otherwise.
  std::string recommended;
};

/// A fit with chi2/dof at or below this is at the noise floor (the residuals are explained).
inline constexpr double kExplainedChi2Dof = 1.5;

/// Fits `model`, then each catalogue term it lacks (and the next order of each temperature
/// polynomial it has) added in turn, ranked by the change in BIC; correlates the residuals with
/// every signal of error-model.md, their squares and absolute values. One pass over the samples
/// serves every candidate.
Diagnosis diagnose(const RunData& data, const Model& model, const FitOptions& options = {});

/// The `calstand diagnose --json` document.
nlohmann::json diagnosis_to_json(const Diagnosis& d);

}  // namespace calstand::solver

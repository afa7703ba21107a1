#pragma once
// Held-out prediction, the check a suggested term must pass besides its BIC (suggest.cpp): the
// run's steps split into parts, each predicted by the model fitted to the rest.

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "solver/fit.hpp"
#include "solver/model.hpp"
#include "solver/step_noise.hpp"
#include "solver/step_summary.hpp"

namespace calstand::solver::detail {

/// Parts of the run to hold out in turn: each temperature plateau when there are three or more
/// (a term that is physics extrapolates to a temperature it was not fitted at), else steps
/// interleaved into five folds.
struct Folds {
  std::vector<std::vector<std::size_t>> parts;
  std::string how;
};

/// The folds of `steps`: by temperature plateau when `by_plateau` and the run has three or
/// more, else steps interleaved.
Folds make_folds(const std::vector<StepSummary>& steps, bool by_plateau);

/// Chi-square of each held-out part predicted by `model` fitted to the rest, summed, with the
/// rows it covers; +infinity when some part leaves too little to fit.
std::pair<double, int> held_out_chi2(const std::vector<StepSummary>& steps, const Model& model,
                                     const StepNoise& noise, const FitOptions& options,
                                     const Folds& folds);

}  // namespace calstand::solver::detail

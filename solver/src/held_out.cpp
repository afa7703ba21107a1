#include "held_out.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "solver/groups.hpp"

namespace calstand::solver::detail {
namespace {

// Folds of interleaved steps when the run has fewer than three temperature plateaus.
constexpr std::size_t kStepFolds = 5;

}  // namespace

Folds make_folds(const std::vector<StepSummary>& steps, bool by_plateau) {
  Folds f;
  const std::vector<double> plateaus = temperature_plateaus(steps);
  if (by_plateau && plateaus.size() >= 3) {
    f.parts.resize(plateaus.size());
    for (std::size_t i = 0; i < steps.size(); ++i) {
      const double temperature_c = steps[i].signals[0];
      std::size_t nearest = 0;
      for (std::size_t p = 1; p < plateaus.size(); ++p) {
        if (std::abs(temperature_c - plateaus[p]) < std::abs(temperature_c - plateaus[nearest])) {
          nearest = p;
        }
      }
      f.parts[nearest].push_back(i);
    }
    f.how = fmt::format("{} temperature plateaus held out in turn", plateaus.size());
    return f;
  }
  const std::size_t k = std::min(kStepFolds, steps.size());
  f.parts.resize(k);
  for (std::size_t i = 0; i < steps.size(); ++i) f.parts[i % k].push_back(i);
  f.how = fmt::format("{} folds of interleaved steps held out in turn", k);
  return f;
}

std::pair<double, int> held_out_chi2(const std::vector<StepSummary>& steps, const Model& model,
                                     const StepNoise& noise, const FitOptions& options,
                                     const Folds& folds) {
  double chi2 = 0.0;
  int rows = 0;
  for (const auto& part : folds.parts) {
    std::vector<bool> held(steps.size(), false);
    for (std::size_t i : part) held[i] = true;
    std::vector<StepSummary> train, test;
    for (std::size_t i = 0; i < steps.size(); ++i) (held[i] ? test : train).push_back(steps[i]);
    FitResult fit;
    try {
      fit = fit_model(train, model, noise, options);
    } catch (const core::InputError&) {
      return {std::numeric_limits<double>::infinity(), 0};
    }
    for (int c : fit_channels(options.rows)) {
      Eigen::VectorXd e(static_cast<Eigen::Index>(test.size()));
      for (std::size_t i = 0; i < test.size(); ++i) {
        const StepSummary& s = test[i];
        e[static_cast<Eigen::Index>(i)] =
            s.measured[c] - s.reference[c] - s.regressors.row(c).dot(fit.values);
      }
      const Eigen::LLT<Eigen::MatrixXd> llt(noise.covariance(c, test));
      chi2 += e.dot(llt.solve(e));
      rows += static_cast<int>(test.size());
    }
  }
  return {chi2, rows};
}

}  // namespace calstand::solver::detail

#pragma once
// The Levenberg-Marquardt solve the calibrations without a table share (gravity_norm.cpp,
// gyro_integration.cpp): one parameter block, some parameters held at their values (those the
// data do not determine), tolerances tight enough that the covariance is taken at the minimum.

#include <ceres/ceres.h>

#include <vector>

namespace calstand::solver::detail {

struct CeresOutcome {
  int iterations = 0;
  bool converged = false;
};

/// Solves `problem`, whose one parameter block is `p` (`np` values), with the parameters in
/// `fixed` held at their values in `p`.
inline CeresOutcome solve_holding(ceres::Problem& problem, double* p, int np,
                                  const std::vector<int>& fixed, int max_iterations) {
  if (static_cast<int>(fixed.size()) == np) {
    problem.SetParameterBlockConstant(p);
  } else if (!fixed.empty()) {
    problem.SetManifold(p, new ceres::SubsetManifold(np, fixed));
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.function_tolerance = 1e-14;
  so.gradient_tolerance = 1e-14;
  so.parameter_tolerance = 1e-12;
  so.logging_type = ceres::SILENT;
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  return {static_cast<int>(summary.iterations.size()),
          summary.termination_type == ceres::CONVERGENCE};
}

}  // namespace calstand::solver::detail

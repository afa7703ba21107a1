#include "solver/gravity_norm.hpp"

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include "core/error.hpp"
#include "core/site.hpp"

namespace calstand::solver {

namespace {

constexpr const char* kNormWhere = "gravity norm";
constexpr double kMg = 1e-3 * core::kStandardGravity;  // m/s^2 per mg

// Parameters (internal): b x y z [m/s^2], s x y z [1], m yx zx zy [rad].
constexpr int kNormParams = 9;

struct NormResidual {
  Eigen::Vector3d a;
  double g;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* p, T* r) const {
    const T f0 = (T(a[0]) - p[0]) / (1.0 + p[3]);
    const T f1 = (T(a[1]) - p[1] - p[6] * f0) / (1.0 + p[4]);
    const T f2 = (T(a[2]) - p[2] - p[7] * f0 - p[8] * f1) / (1.0 + p[5]);
    r[0] = (ceres::sqrt(f0 * f0 + f1 * f1 + f2 * f2) - g) * inv_sigma;
    return true;
  }
};

TriadModel norm_model(const double* p) {
  TriadModel m;
  m.bias = Eigen::Vector3d(p[0], p[1], p[2]);
  m.scale_ppm = 1e6 * Eigen::Vector3d(p[3], p[4], p[5]);
  m.misalignment(1, 0) = p[6];
  m.misalignment(2, 0) = p[7];
  m.misalignment(2, 1) = p[8];
  return m;
}

const char* const kNormNames[kNormParams] = {
    "accel_bias.x",          "accel_bias.y",          "accel_bias.z",
    "accel_scale.x",         "accel_scale.y",         "accel_scale.z",
    "accel_misalignment.yx", "accel_misalignment.zx", "accel_misalignment.zy"};

struct NormSolve {
  std::array<double, kNormParams> p{};
  Eigen::MatrixXd J;  // weighted, internal units
  Eigen::VectorXd r;  // weighted
  int iterations = 0;
  bool converged = false;
};

// Solves from `start` with the `fixed` parameters held at their start values
// (max_iterations 0: only evaluates at the start), then evaluates the weighted Jacobian and
// residuals.
NormSolve norm_solve(const std::vector<std::unique_ptr<ceres::CostFunction>>& costs,
                     const std::array<double, kNormParams>& start, const std::vector<int>& fixed,
                     int max_iterations) {
  NormSolve s;
  s.p = start;
  if (max_iterations > 0) {
    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    for (const auto& c : costs) problem.AddResidualBlock(c.get(), nullptr, s.p.data());
    if (static_cast<int>(fixed.size()) == kNormParams) {
      problem.SetParameterBlockConstant(s.p.data());
    } else if (!fixed.empty()) {
      problem.SetManifold(s.p.data(), new ceres::SubsetManifold(kNormParams, fixed));
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
    s.iterations = static_cast<int>(summary.iterations.size());
    s.converged = summary.termination_type == ceres::CONVERGENCE;
  }

  const auto n = static_cast<Eigen::Index>(costs.size());
  s.J.resize(n, kNormParams);
  s.r.resize(n);
  const double* params[] = {s.p.data()};
  double jac[kNormParams];
  double* jacs[] = {jac};
  for (Eigen::Index k = 0; k < n; ++k) {
    double res = 0.0;
    costs[static_cast<std::size_t>(k)]->Evaluate(params, &res, jacs);
    s.r[k] = res;
    for (int j = 0; j < kNormParams; ++j) s.J(k, j) = jac[j];
  }
  return s;
}

}  // namespace

GravityNormResult calibrate_accel_gravity_norm(std::span<const core::ImuSample> samples,
                                               std::span<const StaticInterval> intervals,
                                               const GravityNormOptions& o) {
  if (!(o.gravity_mps2 > 0.0) || !std::isfinite(o.gravity_mps2)) {
    throw core::InputError(kNormWhere, "local gravity (gravity_mps2) must be given and positive");
  }
  GravityNormResult out;
  out.gravity_mps2 = o.gravity_mps2;
  for (std::size_t i = 0; i < intervals.size(); ++i) {
    const StaticInterval& in = intervals[i];
    if (in.initial_rest && !o.use_initial_rest) continue;
    if (in.end > samples.size() || in.begin >= in.end) {
      throw core::InputError(kNormWhere, fmt::format("interval {} lies outside the samples", i));
    }
    const StaticMean m = static_mean(samples, in.begin, in.end, TriadSensor::kAccel);
    GravityNormPose p;
    p.interval = i;
    p.start_s = in.start_s;
    p.end_s = in.end_s;
    p.samples = m.count;
    p.mean_mps2 = m.mean;
    p.sigma_mean_mps2 = m.sigma_of_mean;
    out.poses.push_back(p);
  }
  const int needed = std::max(o.min_poses, kNormParams);
  if (static_cast<int>(out.poses.size()) < needed) {
    throw core::InputError(
        kNormWhere,
        fmt::format("{} static poses are needed for bias, scale and misalignment of the "
                    "accelerometers (9 unknowns), found {}: record more poses, "
                    "spread over every direction",
                    needed, out.poses.size()));
  }

  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  for (const GravityNormPose& p : out.poses) {
    const Eigen::Vector3d u = p.mean_mps2.normalized();
    double sigma = std::sqrt(u.cwiseAbs2().dot(p.sigma_mean_mps2.cwiseAbs2()));
    sigma = std::max(sigma, 1e-9 * o.gravity_mps2);
    costs.emplace_back(new ceres::AutoDiffCostFunction<NormResidual, 1, kNormParams>(
        new NormResidual{p.mean_mps2, o.gravity_mps2, 1.0 / sigma}));
  }

  // What the poses determine is a property of their directions: judged at the nominal model
  // (a fit would first spend the undetermined directions on noise).
  const std::array<double, kNormParams> nominal_p{};
  const NormSolve nominal = norm_solve(costs, nominal_p, {}, 0);
  Eigen::VectorXd natural(kNormParams);
  natural << o.gravity_mps2, o.gravity_mps2, o.gravity_mps2, 1, 1, 1, 1, 1, 1;
  const std::vector<int> fixed = undetermined_columns(nominal.J, natural, o.null_tolerance);
  // Undetermined parameters are held, not fitted (left free they would bend the others: an
  // axis that never feels gravity could add any f_i^2 to the norm). An undetermined bias is
  // held at that axis's mean reading over the poses (the axis then says "no specific force",
  // which is what its poses show), the others at 0.
  std::array<double, kNormParams> start{};
  for (int j : fixed) {
    if (j < 3) {
      double mean = 0.0;
      for (const GravityNormPose& p : out.poses) mean += p.mean_mps2[j];
      start[static_cast<std::size_t>(j)] = mean / static_cast<double>(out.poses.size());
    }
  }
  const NormSolve s = norm_solve(costs, start, fixed, o.max_iterations);
  std::vector<bool> is_fixed(kNormParams, false);
  for (int j : fixed) {
    is_fixed[static_cast<std::size_t>(j)] = true;
    out.undetermined.push_back(kNormNames[j]);
  }
  out.iterations = s.iterations;
  out.converged = s.converged;
  out.accel = norm_model(s.p.data());

  // Covariance of the free parameters.
  std::vector<int> free;
  for (int j = 0; j < kNormParams; ++j) {
    if (!is_fixed[static_cast<std::size_t>(j)]) free.push_back(j);
  }
  const auto nf = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd Jf(s.J.rows(), nf);
  for (Eigen::Index c = 0; c < nf; ++c) Jf.col(c) = s.J.col(free[static_cast<std::size_t>(c)]);
  Eigen::MatrixXd cov_free = Eigen::MatrixXd::Zero(nf, nf);
  if (nf > 0) {
    cov_free = (Jf.transpose() * Jf).ldlt().solve(Eigen::MatrixXd::Identity(nf, nf));
  }
  out.chi2 = s.r.squaredNorm();
  out.dof = static_cast<int>(out.poses.size()) - static_cast<int>(nf);
  out.chi2_per_dof = out.dof > 0 ? out.chi2 / out.dof : 0.0;
  if (o.scale_sigmas_by_residual && out.dof > 0 && out.chi2_per_dof > 1.0) {
    out.sigma_scale = std::sqrt(out.chi2_per_dof);
    out.sigmas_scaled = true;
  }
  // To contract units: scale in ppm.
  Eigen::VectorXd unit = Eigen::VectorXd::Ones(kNormParams);
  unit.segment<3>(3).setConstant(1e6);
  for (Eigen::Index a = 0; a < nf; ++a) {
    for (Eigen::Index b = 0; b < nf; ++b) {
      const int i = free[static_cast<std::size_t>(a)];
      const int j = free[static_cast<std::size_t>(b)];
      out.covariance(i, j) = cov_free(a, b) * unit[i] * unit[j] * out.sigma_scale * out.sigma_scale;
    }
  }

  // Named estimates (12, the three by convention included).
  out.parameters = triad_estimates("accel", out.accel);
  for (TriadEstimate& e : out.parameters) {
    if (e.name == "accel_misalignment.xy" || e.name == "accel_misalignment.xz" ||
        e.name == "accel_misalignment.yz") {
      e.status = EstimateStatus::kFixedByConvention;
      continue;
    }
    for (int j = 0; j < kNormParams; ++j) {
      if (e.name == kNormNames[j]) {
        e.sigma = std::sqrt(std::max(0.0, out.covariance(j, j)));
        if (is_fixed[static_cast<std::size_t>(j)]) e.status = EstimateStatus::kUndetermined;
      }
    }
  }

  // Pose residuals.
  double sum_sq = 0.0;
  for (GravityNormPose& p : out.poses) {
    const Eigen::Vector3d f = out.accel.correct(p.mean_mps2);
    p.norm_mps2 = f.norm();
    p.up_A = f.normalized();
    p.residual_mg = (p.norm_mps2 - o.gravity_mps2) / kMg;
    p.sigma_mg = std::sqrt(p.up_A.cwiseAbs2().dot(p.sigma_mean_mps2.cwiseAbs2())) / kMg;
    sum_sq += p.residual_mg * p.residual_mg;
    out.max_abs_residual_mg = std::max(out.max_abs_residual_mg, std::abs(p.residual_mg));
  }
  out.rms_residual_mg = std::sqrt(sum_sq / static_cast<double>(out.poses.size()));

  std::string quality;
  if (out.dof <= 0) {
    quality =
        "no redundancy (as many poses as unknowns): the sigmas come from the pose means' "
        "noise alone, unchecked by the residual";
  } else if (out.sigmas_scaled) {
    quality = fmt::format(
        "chi2/dof {:.3g} against the pose means' own noise: the poses scatter more than their "
        "noise (a bias that wanders between poses, a hand that moves, or an effect the model "
        "lacks), so every sigma is scaled by {:.3g}",
        out.chi2_per_dof, out.sigma_scale);
  } else {
    quality = fmt::format("chi2/dof {:.3g}: the poses agree to their own noise", out.chi2_per_dof);
  }
  std::string missing = "every parameter is determined";
  if (!out.undetermined.empty()) {
    missing = "the poses do not determine ";
    for (std::size_t i = 0; i < out.undetermined.size(); ++i) {
      missing += (i > 0 ? ", " : "") + out.undetermined[i];
    }
    missing +=
        " (their values only absorb the unexcited axis: do not use them; add poses that tip "
        "those axes)";
  }
  out.summary = fmt::format(
      "accelerometer by the gravity norm on {} poses: |f| - g RMS {:.3g} mg, largest {:.3g} mg; "
      "{}; {}",
      out.poses.size(), out.rms_residual_mg, out.max_abs_residual_mg, quality, missing);
  return out;
}

ThresholdSearch detect_and_calibrate_accel(std::span<const core::ImuSample> samples,
                                           const StaticDetectorOptions& detector,
                                           const GravityNormOptions& options,
                                           const std::vector<double>& multiples) {
  ThresholdSearch out;
  bool have = false;
  for (double k : multiples) {
    StaticDetectorOptions d = detector;
    d.rule = ThresholdRule::kMultiple;
    d.threshold_multiple = k;
    StaticDetection det = detect_static_intervals(samples, d);
    ThresholdSearch::Candidate c;
    c.multiple = k;
    c.intervals = det.intervals.size();
    try {
      GravityNormResult fit = calibrate_accel_gravity_norm(samples, det.intervals, options);
      c.fitted = true;
      c.rms_residual_mg = fit.rms_residual_mg;
      if (!have || fit.rms_residual_mg < out.fit.rms_residual_mg) {
        out.fit = std::move(fit);
        out.detection = std::move(det);
        out.chosen_multiple = k;
        have = true;
      }
    } catch (const core::InputError&) {
      // too few intervals at this multiple
    }
    out.candidates.push_back(c);
  }
  if (!have) {
    throw core::InputError(kNormWhere, fmt::format("no threshold multiple gives {} static poses",
                                                   std::max(options.min_poses, kNormParams)));
  }
  out.detection.rule_text += fmt::format(
      "; multiple chosen by the smallest |f|-g residual among {} candidates", multiples.size());
  return out;
}

nlohmann::json gravity_norm_to_json(const GravityNormResult& r) {
  nlohmann::json j;
  j["method"] = "gravity_norm";
  j["frame"] = kAccelTriadFrameText;
  j["gravity_mps2"] = r.gravity_mps2;
  j["parameters"] = triad_estimates_to_json(r.parameters);
  nlohmann::json names = nlohmann::json::array();
  for (const char* n : kNormNames) names.push_back(n);
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < kNormParams; ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (int k = 0; k < kNormParams; ++k) row.push_back(r.covariance(i, k));
    rows.push_back(row);
  }
  j["covariance"] = {{"names", names}, {"matrix", rows}};
  j["undetermined"] = r.undetermined;
  j["quality"] = {{"poses", r.poses.size()},
                  {"rms_residual_mg", r.rms_residual_mg},
                  {"max_abs_residual_mg", r.max_abs_residual_mg},
                  {"chi2", r.chi2},
                  {"dof", r.dof},
                  {"chi2_per_dof", r.chi2_per_dof},
                  {"sigma_scale", r.sigma_scale},
                  {"sigmas_scaled", r.sigmas_scaled},
                  {"summary", r.summary}};
  nlohmann::json poses = nlohmann::json::array();
  for (const GravityNormPose& p : r.poses) {
    poses.push_back({{"interval", p.interval},
                     {"start_s", p.start_s},
                     {"end_s", p.end_s},
                     {"samples", p.samples},
                     {"mean_mps2", {p.mean_mps2.x(), p.mean_mps2.y(), p.mean_mps2.z()}},
                     {"up_A", {p.up_A.x(), p.up_A.y(), p.up_A.z()}},
                     {"norm_mps2", p.norm_mps2},
                     {"residual_mg", p.residual_mg},
                     {"sigma_mg", p.sigma_mg}});
  }
  j["poses"] = poses;
  j["solver"] = {{"iterations", r.iterations}, {"converged", r.converged}};
  return j;
}

}  // namespace calstand::solver

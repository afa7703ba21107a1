#include "tablefree/gravity_norm.hpp"

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include "ceres_solve.hpp"
#include "core/error.hpp"
#include "core/site.hpp"

namespace calstand::solver {

namespace {

constexpr const char* kNormWhere = "gravity norm";
constexpr double kMg = 1e-3 * core::kStandardGravity;  // m/s^2 per mg

// Parameters (internal): b x y z [m/s^2], s x y z [1], m yx zx zy [rad], and with the
// quadratic q x y z [1e6 ug/g^2: measured += g0 q (f/g0)^2].
constexpr int kNormParams = 9;
constexpr int kNormParamsQuadratic = 12;
// Fixed-point steps of f = T^-1 (a - b - q(f)): each shrinks the error by 2e-6 k |f|/g0 (below
// 1e-2 for any plausible k), so three leave it far below the noise.
constexpr int kQuadraticIterations = 3;

// The calibrated force of a raw reading `a` under internal parameters p (T lower triangular:
// forward substitution).
template <typename T>
void norm_correct(const T* p, bool quadratic, const Eigen::Vector3d& a, T f[3]) {
  T q[3] = {T(0.0), T(0.0), T(0.0)};
  for (int it = 0; it <= (quadratic ? kQuadraticIterations : 0); ++it) {
    if (it > 0) {
      for (int i = 0; i < 3; ++i) q[i] = p[9 + i] * f[i] * f[i] / core::kStandardGravity;
    }
    f[0] = (T(a[0]) - p[0] - q[0]) / (1.0 + p[3]);
    f[1] = (T(a[1]) - p[1] - q[1] - p[6] * f[0]) / (1.0 + p[4]);
    f[2] = (T(a[2]) - p[2] - q[2] - p[7] * f[0] - p[8] * f[1]) / (1.0 + p[5]);
  }
}

// |f| - g of one pose mean [m/s^2], unweighted (the weights are the whitening of norm_solve).
struct NormResidual {
  Eigen::Vector3d a;
  double g;
  bool quadratic;
  template <typename T>
  bool operator()(const T* p, T* r) const {
    T f[3];
    norm_correct(p, quadratic, a, f);
    r[0] = ceres::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) - g;
    return true;
  }
};

// Every pose's residual in one block, whitened by the lower Cholesky factor L of their
// covariance: L^-1 r and L^-1 J (generalised least squares as ordinary least squares).
class WhitenedNormCost : public ceres::CostFunction {
 public:
  WhitenedNormCost(const std::vector<std::unique_ptr<ceres::CostFunction>>& poses,
                   const Eigen::MatrixXd& L, int parameters)
      : poses_(poses), L_(L), np_(parameters) {
    set_num_residuals(static_cast<int>(poses.size()));
    mutable_parameter_block_sizes()->push_back(parameters);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const auto n = static_cast<Eigen::Index>(poses_.size());
    Eigen::VectorXd r(n);
    Eigen::MatrixXd J(n, np_);
    std::vector<double> row(static_cast<std::size_t>(np_));
    double* rows[] = {row.data()};
    for (Eigen::Index k = 0; k < n; ++k) {
      if (!poses_[static_cast<std::size_t>(k)]->Evaluate(parameters, &r[k],
                                                         jacobians ? rows : nullptr)) {
        return false;
      }
      if (jacobians) {
        for (int j = 0; j < np_; ++j) J(k, j) = row[static_cast<std::size_t>(j)];
      }
    }
    const auto lower = L_.triangularView<Eigen::Lower>();
    Eigen::Map<Eigen::VectorXd>(residuals, n) = lower.solve(r);
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          jacobians[0], n, np_) = lower.solve(J);
    }
    return true;
  }

 private:
  const std::vector<std::unique_ptr<ceres::CostFunction>>& poses_;
  const Eigen::MatrixXd& L_;
  int np_;
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

const char* const kNormNames[kNormParamsQuadratic] = {
    "accel_bias.x",          "accel_bias.y",      "accel_bias.z",          "accel_scale.x",
    "accel_scale.y",         "accel_scale.z",     "accel_misalignment.yx", "accel_misalignment.zx",
    "accel_misalignment.zy", "accel_quadratic.x", "accel_quadratic.y",     "accel_quadratic.z"};

struct NormSolve {
  std::vector<double> p;
  Eigen::MatrixXd J;      // whitened, internal units
  Eigen::VectorXd r;      // whitened
  Eigen::MatrixXd J_raw;  // unwhitened [m/s^2 per internal unit]
  Eigen::VectorXd r_raw;  // |f| - g [m/s^2]
  int iterations = 0;
  bool converged = false;
};

// Solves from `start` with the `fixed` parameters held at their start values, the residuals
// whitened by L (max_iterations 0: only evaluates at the start), then evaluates the Jacobian
// and residuals, whitened and raw.
NormSolve norm_solve(const std::vector<std::unique_ptr<ceres::CostFunction>>& costs,
                     const Eigen::MatrixXd& L, const std::vector<double>& start,
                     const std::vector<int>& fixed, int max_iterations) {
  const int np = static_cast<int>(start.size());
  NormSolve s;
  s.p = start;
  WhitenedNormCost whitened(costs, L, np);
  if (max_iterations > 0) {
    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    problem.AddResidualBlock(&whitened, nullptr, s.p.data());
    const detail::CeresOutcome solved =
        detail::solve_holding(problem, s.p.data(), np, fixed, max_iterations);
    s.iterations = solved.iterations;
    s.converged = solved.converged;
  }

  const auto n = static_cast<Eigen::Index>(costs.size());
  s.J_raw.resize(n, np);
  s.r_raw.resize(n);
  const double* params[] = {s.p.data()};
  std::vector<double> jac(static_cast<std::size_t>(np));
  double* jacs[] = {jac.data()};
  for (Eigen::Index k = 0; k < n; ++k) {
    costs[static_cast<std::size_t>(k)]->Evaluate(params, &s.r_raw[k], jacs);
    for (int j = 0; j < np; ++j) s.J_raw(k, j) = jac[static_cast<std::size_t>(j)];
  }
  const auto lower = L.triangularView<Eigen::Lower>();
  s.r = lower.solve(s.r_raw);
  s.J = lower.solve(s.J_raw);
  return s;
}

}  // namespace

Eigen::Vector3d correct_accel(const TriadModel& accel, const Eigen::Vector3d& quadratic_ug_per_g2,
                              const Eigen::Vector3d& measured) {
  Eigen::Vector3d f = accel.correct(measured);
  if (quadratic_ug_per_g2.isZero()) return f;
  for (int it = 0; it < kQuadraticIterations; ++it) {
    const Eigen::Vector3d q = 1e-6 * core::kStandardGravity *
                              quadratic_ug_per_g2.cwiseProduct(f.cwiseAbs2()) /
                              (core::kStandardGravity * core::kStandardGravity);
    f = accel.correct(measured - q);
  }
  return f;
}

Eigen::Vector3d correct_accel(const GravityNormResult& r, const Eigen::Vector3d& measured) {
  return correct_accel(r.accel, r.quadratic_ug_per_g2, measured);
}

GravityNormResult calibrate_accel_gravity_norm(std::span<const core::ImuSample> samples,
                                               std::span<const StaticInterval> intervals,
                                               const GravityNormOptions& o) {
  if (!(o.gravity_mps2 > 0.0) || !std::isfinite(o.gravity_mps2)) {
    throw core::InputError(kNormWhere, "local gravity (gravity_mps2) must be given and positive");
  }
  GravityNormResult out;
  out.gravity_mps2 = o.gravity_mps2;
  out.quadratic_fitted = o.fit_quadratic;
  const int np = o.fit_quadratic ? kNormParamsQuadratic : kNormParams;
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
  const int needed = std::max(o.min_poses, np);
  if (static_cast<int>(out.poses.size()) < needed) {
    throw core::InputError(
        kNormWhere,
        fmt::format("{} static poses are needed for bias, scale and misalignment of the "
                    "accelerometers ({} unknowns), found {}: record more poses, "
                    "spread over every direction",
                    needed, np, out.poses.size()));
  }

  // The poses as the noise model sees them: white variance along the raw gravity direction.
  const auto n = static_cast<Eigen::Index>(out.poses.size());
  const double t0 = samples.empty() ? 0.0 : samples.front().receive_time_s;
  std::vector<PoseSpan> spans;
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  Eigen::MatrixXd L_white = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const GravityNormPose& p = out.poses[static_cast<std::size_t>(k)];
    const Eigen::Vector3d u = p.mean_mps2.normalized();
    double sigma = std::sqrt(u.cwiseAbs2().dot(p.sigma_mean_mps2.cwiseAbs2()));
    sigma = std::max(sigma, 1e-9 * o.gravity_mps2);
    L_white(k, k) = sigma;
    spans.push_back({p.start_s - t0, p.end_s - t0, u, sigma * sigma});
    auto* residual = new NormResidual{p.mean_mps2, o.gravity_mps2, o.fit_quadratic};
    if (o.fit_quadratic) {
      costs.emplace_back(
          new ceres::AutoDiffCostFunction<NormResidual, 1, kNormParamsQuadratic>(residual));
    } else {
      costs.emplace_back(new ceres::AutoDiffCostFunction<NormResidual, 1, kNormParams>(residual));
    }
  }

  // What the poses determine is a property of their directions: judged at the nominal model
  // (a fit would first spend the undetermined directions on noise).
  const std::vector<double> nominal_p(static_cast<std::size_t>(np), 0.0);
  const NormSolve nominal = norm_solve(costs, L_white, nominal_p, {}, 0);
  // Natural units: a bias of g, a unit scale, a radian and q = 1 (k = 1e6 ug/g^2) each move a
  // reading by about g.
  Eigen::VectorXd natural = Eigen::VectorXd::Ones(np);
  natural.head<3>().setConstant(o.gravity_mps2);
  const std::vector<int> fixed = undetermined_columns(nominal.J, natural, o.null_tolerance);
  // Undetermined parameters are held, not fitted (left free they would bend the others: an
  // axis that never feels gravity could add any f_i^2 to the norm). An undetermined bias is
  // held at that axis's mean reading over the poses (the axis then says "no specific force",
  // which is what its poses show), the others at 0.
  std::vector<double> start(static_cast<std::size_t>(np), 0.0);
  for (int j : fixed) {
    if (j < 3) {
      double mean = 0.0;
      for (const GravityNormPose& p : out.poses) mean += p.mean_mps2[j];
      start[static_cast<std::size_t>(j)] = mean / static_cast<double>(out.poses.size());
    }
  }
  std::vector<bool> is_fixed(static_cast<std::size_t>(np), false);
  for (int j : fixed) {
    is_fixed[static_cast<std::size_t>(j)] = true;
    out.undetermined.push_back(kNormNames[j]);
  }
  std::vector<int> free;
  for (int j = 0; j < np; ++j) {
    if (!is_fixed[static_cast<std::size_t>(j)]) free.push_back(j);
  }
  const auto nf = static_cast<Eigen::Index>(free.size());
  const auto free_columns = [&](const Eigen::MatrixXd& J) {
    Eigen::MatrixXd Jf(J.rows(), nf);
    for (Eigen::Index c = 0; c < nf; ++c) Jf.col(c) = J.col(free[static_cast<std::size_t>(c)]);
    return Jf;
  };

  // First weighed by the white noise alone; the noise model from its residuals; then, when
  // the model holds more than white noise, again by generalised least squares.
  NormSolve s = norm_solve(costs, L_white, start, fixed, o.max_iterations);
  if (o.estimate_pose_noise) {
    out.noise = estimate_pose_noise(spans, s.r_raw, free_columns(s.J_raw));
  } else {
    out.noise.residuals = static_cast<int>(n);
    out.noise.dof = static_cast<int>(n - nf);
    out.noise.description =
        "white noise of the pose means alone (noise model not estimated, as "
        "asked)";
  }
  if (out.noise.wander.kind != WanderKind::kNone || out.noise.extra_variance > 0.0) {
    const Eigen::LLT<Eigen::MatrixXd> llt(out.noise.covariance(spans));
    if (llt.info() == Eigen::Success) {
      const Eigen::MatrixXd L = llt.matrixL();
      const int first_iterations = s.iterations;
      s = norm_solve(costs, L, s.p, fixed, o.max_iterations);
      s.iterations += first_iterations;
    }
  }
  out.iterations = s.iterations;
  out.converged = s.converged;
  out.accel = norm_model(s.p.data());
  if (o.fit_quadratic) {
    out.quadratic_ug_per_g2 = 1e6 * Eigen::Vector3d(s.p[9], s.p[10], s.p[11]);
  }

  // Covariance of the free parameters from the whitened Jacobian.
  const Eigen::MatrixXd Jf = free_columns(s.J);
  Eigen::MatrixXd cov_free = Eigen::MatrixXd::Zero(nf, nf);
  if (nf > 0) {
    cov_free = (Jf.transpose() * Jf).ldlt().solve(Eigen::MatrixXd::Identity(nf, nf));
  }
  // chi2 against the white noise alone, whatever the weights.
  out.chi2 = L_white.diagonal().cwiseInverse().cwiseProduct(s.r_raw).squaredNorm();
  out.dof = static_cast<int>(n) - static_cast<int>(nf);
  out.chi2_per_dof = out.dof > 0 ? out.chi2 / out.dof : 0.0;
  // ... and against the noise model the weights came from (white alone when there is none).
  out.chi2_noise_model = s.r.squaredNorm();
  if (!out.noise.estimated && o.scale_sigmas_by_residual && out.dof > 0 && out.chi2_per_dof > 1.0) {
    out.sigma_scale = std::sqrt(out.chi2_per_dof);
    out.sigmas_scaled = true;
  }
  // To contract units: scale in ppm, quadratic in ug/g^2.
  Eigen::VectorXd unit = Eigen::VectorXd::Ones(np);
  unit.segment<3>(3).setConstant(1e6);
  if (o.fit_quadratic) unit.segment<3>(9).setConstant(1e6);
  out.covariance = Eigen::MatrixXd::Zero(np, np);
  for (int j = 0; j < np; ++j) out.covariance_names.emplace_back(kNormNames[j]);
  for (Eigen::Index a = 0; a < nf; ++a) {
    for (Eigen::Index b = 0; b < nf; ++b) {
      const int i = free[static_cast<std::size_t>(a)];
      const int j = free[static_cast<std::size_t>(b)];
      out.covariance(i, j) = cov_free(a, b) * unit[i] * unit[j] * out.sigma_scale * out.sigma_scale;
    }
  }

  // Named estimates (12, the three by convention included; then the quadratic).
  out.parameters = triad_estimates("accel", out.accel);
  if (o.fit_quadratic) {
    for (int i = 0; i < 3; ++i) {
      out.parameters.push_back({kNormNames[9 + i], out.quadratic_ug_per_g2[i], 0.0, "ug/g^2",
                                EstimateStatus::kEstimated});
    }
  }
  for (TriadEstimate& e : out.parameters) {
    if (e.name == "accel_misalignment.xy" || e.name == "accel_misalignment.xz" ||
        e.name == "accel_misalignment.yz") {
      e.status = EstimateStatus::kFixedByConvention;
      continue;
    }
    for (int j = 0; j < np; ++j) {
      if (e.name == kNormNames[j]) {
        e.sigma = std::sqrt(std::max(0.0, out.covariance(j, j)));
        if (is_fixed[static_cast<std::size_t>(j)]) e.status = EstimateStatus::kUndetermined;
      }
    }
  }

  // Pose residuals.
  double sum_sq = 0.0;
  for (GravityNormPose& p : out.poses) {
    const Eigen::Vector3d f = correct_accel(out, p.mean_mps2);
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
  } else if (out.noise.estimated) {
    quality = fmt::format(
        "chi2/dof {:.3g} against the pose means' white noise; {}; the weights and sigmas "
        "follow that noise model",
        out.chi2_per_dof, out.noise.description);
  } else if (out.sigmas_scaled) {
    quality = fmt::format(
        "chi2/dof {:.3g} against the pose means' own noise: the poses scatter more than their "
        "noise (a bias that wanders between poses, a hand that moves, or an effect the model "
        "lacks), so every sigma is scaled by {:.3g} ({})",
        out.chi2_per_dof, out.sigma_scale, out.noise.description);
  } else {
    quality = fmt::format("chi2/dof {:.3g}: the poses agree to their own noise ({})",
                          out.chi2_per_dof, out.noise.description);
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
      "accelerometer by the gravity norm on {} poses{}: |f| - g RMS {:.3g} mg, largest {:.3g} "
      "mg; {}; {}",
      out.poses.size(), o.fit_quadratic ? " (with accel_quadratic)" : "", out.rms_residual_mg,
      out.max_abs_residual_mg, quality, missing);
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
    throw core::InputError(
        kNormWhere,
        fmt::format("no threshold multiple gives {} static poses",
                    std::max(options.min_poses,
                             options.fit_quadratic ? kNormParamsQuadratic : kNormParams)));
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
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index i = 0; i < r.covariance.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index k = 0; k < r.covariance.cols(); ++k) row.push_back(r.covariance(i, k));
    rows.push_back(row);
  }
  j["covariance"] = {{"names", r.covariance_names}, {"matrix", rows}};
  j["undetermined"] = r.undetermined;
  j["quality"] = {{"poses", r.poses.size()},
                  {"rms_residual_mg", r.rms_residual_mg},
                  {"max_abs_residual_mg", r.max_abs_residual_mg},
                  {"chi2", r.chi2},
                  {"dof", r.dof},
                  {"chi2_per_dof", r.chi2_per_dof},
                  {"chi2_noise_model", r.chi2_noise_model},
                  {"sigma_scale", r.sigma_scale},
                  {"sigmas_scaled", r.sigmas_scaled},
                  {"summary", r.summary}};
  j["noise_model"] = pose_noise_to_json(r.noise);
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

#include "solver/fit.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <array>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>

#include "core/error.hpp"

namespace calstand::solver {
namespace {

// A whitened regressor column smaller than this share of the largest is zero to rounding.
constexpr double kZeroColumnShare = 1e-12;
// How far above its own noise a parameter at an implausible size must stand for its column to be
// judged in model order (identifiable_columns).
constexpr double kPlausibleSigmas = 3.0;
// How many times a parameter's reach must exceed those it is collinear with to take their span
// (identifiable_columns): far apart, so that two comparable terms (an accelerometer's scale
// asymmetry and quadratic on +-1 g) keep model order.
constexpr double kReachRatio = 100.0;

bool uses_channel(SensorRows rows, int channel) {
  if (rows == SensorRows::kGyro) return channel < kAx;
  if (rows == SensorRows::kAccel) return channel >= kAx;
  return true;
}

/// A channel the unit does not measure (a 5-DoF sensor's missing axis, delivered as NaN):
/// no step has a mean for it. Its rows are left out, so its terms are not determined.
bool unmeasured(const std::vector<StepSummary>& steps, int channel) {
  return std::all_of(steps.begin(), steps.end(),
                     [&](const StepSummary& s) { return std::isnan(s.measured[channel]); });
}

/// Parameters the rules of the physics exclude before any numerics: a temperature polynomial of
/// order k needs k + 1 distinct temperatures, a temperature scale two.
void temperature_rules(const Model& model, std::size_t temperatures, std::vector<bool>& excluded,
                       std::vector<Unidentifiable>& out) {
  for (std::size_t t = 0; t < model.terms().size(); ++t) {
    const ModelTerm& term = model.terms()[t];
    if (!term.info) continue;
    const std::string_view n = term.info->name;
    const auto [first, count] = model.parameter_range(t);
    for (std::size_t p = first; p < first + count; ++p) {
      int order = 0;
      if (term.info->polynomial_order) order = static_cast<int>((p - first) / 3) + 1;
      if (n == "gyro_temp_scale" || n == "accel_temp_scale") order = 1;
      if (order == 0 || static_cast<std::size_t>(order) < temperatures) continue;
      excluded[p] = true;
      out.push_back({model.parameters()[p].name,
                     fmt::format("temperature order {} needs at least {} temperature plateaus "
                                 "(or step temperatures {} degC apart on a ramp); the run has {}",
                                 order, order + 1, kPlateauGapC, temperatures),
                     {}});
    }
  }
}

/// A magnitude no real sensor's parameter reaches, per contract unit: a parameter whose sigma
/// exceeds it is barely excited by the run (fitted to noise), though not collinear with others.
double implausible_sigma(const std::string& unit) {
  static const std::vector<std::pair<std::string, double>> kBounds{
      {"deg/s", 1.0},     {"ppm", 1e4},          {"rad", 0.05},     {"ppm/(deg/s)", 100.0},
      {"(deg/s)/g", 0.1}, {"deg/s/degC^k", 0.1}, {"ppm/degC", 1e3}, {"m/s^2", 1.0},
      {"ug/g^2", 1e4},    {"m/s^2/degC^k", 0.1}, {"m", 1.0}};
  for (const auto& [u, bound] : kBounds) {
    if (u == unit) return bound;
  }
  return std::numeric_limits<double>::infinity();  // custom terms: the user's scale
}

/// chi2 and degrees of freedom of the gyro rows (0) and the accelerometer rows (1).
struct SensorQuality {
  std::array<double, 2> chi2{0.0, 0.0};
  std::array<int, 2> dof{0, 0};
  double chi2_dof(int sensor) const {
    return dof[static_cast<std::size_t>(sensor)] > 0
               ? chi2[static_cast<std::size_t>(sensor)] / dof[static_cast<std::size_t>(sensor)]
               : std::numeric_limits<double>::quiet_NaN();
  }
};

int sensor_of(const ParameterInfo& p) { return p.sensor == core::TermSensor::kGyro ? 0 : 1; }

SensorQuality sensor_quality(const Eigen::VectorXd& whitened_residual,
                             const std::vector<bool>& gyro_row, const Model& model,
                             const std::vector<Eigen::Index>& accepted) {
  SensorQuality q;
  std::array<int, 2> rows{0, 0};
  for (Eigen::Index r = 0; r < whitened_residual.size(); ++r) {
    const std::size_t sensor = gyro_row[static_cast<std::size_t>(r)] ? 0 : 1;
    q.chi2[sensor] += whitened_residual[r] * whitened_residual[r];
    ++rows[sensor];
  }
  std::array<int, 2> parameters{0, 0};
  for (Eigen::Index p : accepted) {
    ++parameters[static_cast<std::size_t>(
        sensor_of(model.parameters()[static_cast<std::size_t>(p)]))];
  }
  for (std::size_t s = 0; s < 2; ++s) q.dof[s] = rows[s] > 0 ? rows[s] - parameters[s] : 0;
  return q;
}

/// Per accepted parameter, the factor its variance is inflated by: its sensor's chi2/dof when
/// that exceeds 1 (a poor accelerometer fit says nothing about the gyro parameters).
Eigen::VectorXd parameter_inflation(const SensorQuality& q, const Model& model,
                                    const std::vector<Eigen::Index>& accepted, bool inflate) {
  Eigen::VectorXd f = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(accepted.size()));
  if (!inflate) return f;
  for (std::size_t j = 0; j < accepted.size(); ++j) {
    const double c =
        q.chi2_dof(sensor_of(model.parameters()[static_cast<std::size_t>(accepted[j])]));
    if (std::isfinite(c) && c > 1.0) f[static_cast<Eigen::Index>(j)] = c;
  }
  return f;
}

// One judgement of the columns in `order` (Gram-Schmidt on normalised columns, orthogonalised
// twice): each column not `excluded` is taken when it stands out of the span of the ones taken
// before it; why each other one is not taken goes to `out`, and for a (nearly) collinear one
// the taken columns it leans on to `leans_on`.
std::vector<Eigen::Index> judge_columns(
    const Eigen::MatrixXd& A, const Model& model, const std::vector<std::size_t>& order,
    const std::vector<bool>& excluded, const FitOptions& options, std::vector<Unidentifiable>& out,
    std::vector<std::pair<std::size_t, std::vector<std::size_t>>>& leans_on) {
  double largest_column = 0.0;
  for (Eigen::Index c = 0; c < A.cols(); ++c)
    largest_column = std::max(largest_column, A.col(c).norm());
  std::vector<Eigen::Index> accepted;
  Eigen::MatrixXd basis(A.rows(), 0);
  for (const std::size_t p : order) {
    const auto col = static_cast<Eigen::Index>(p);
    const std::string& name = model.parameters()[p].name;
    if (excluded[p]) continue;
    const core::TermSensor sensor = model.parameters()[p].sensor;
    if ((options.rows == SensorRows::kGyro && sensor == core::TermSensor::kAccel) ||
        (options.rows == SensorRows::kAccel && sensor == core::TermSensor::kGyro)) {
      out.push_back({name, "its sensor's rows are not part of this fit", {}});
      continue;
    }
    const double norm = A.col(col).norm();
    // Zero up to rounding counts as zero: a force component at 90 degrees is 6e-16 g, not 0,
    // and normalising it would let rounding noise take a real parameter's place.
    if (!(norm > kZeroColumnShare * largest_column)) {
      out.push_back({name, "the run does not excite it (its regressor is zero in every step)", {}});
      continue;
    }
    Eigen::VectorXd v = A.col(col) / norm;
    for (int pass = 0; pass < 2; ++pass) v -= basis * (basis.transpose() * v);
    const double sine = v.norm();
    if (sine < options.near_collinear_sine) {
      // Which accepted parameters it leans on: the largest contributions of its projection.
      Unidentifiable u;
      u.name = name;
      std::vector<std::size_t> related;
      if (!accepted.empty()) {
        Eigen::MatrixXd Aa(A.rows(), static_cast<Eigen::Index>(accepted.size()));
        for (std::size_t k = 0; k < accepted.size(); ++k)
          Aa.col(static_cast<Eigen::Index>(k)) = A.col(accepted[k]);
        const Eigen::VectorXd coef = Aa.colPivHouseholderQr().solve(A.col(col));
        Eigen::VectorXd contribution(coef.size());
        for (Eigen::Index k = 0; k < coef.size(); ++k)
          contribution[k] = std::abs(coef[k]) * Aa.col(k).norm();
        const double biggest = contribution.maxCoeff();
        for (Eigen::Index k = 0; k < coef.size(); ++k) {
          if (contribution[k] >= 0.1 * biggest) {
            related.push_back(static_cast<std::size_t>(accepted[static_cast<std::size_t>(k)]));
            u.related.push_back(model.parameters()[related.back()].name);
          }
        }
      }
      const std::string with = u.related.empty() ? std::string("the other parameters")
                                                 : fmt::format("{}", fmt::join(u.related, ", "));
      u.reason =
          sine < options.collinear_sine
              ? fmt::format("not determined by this run: its effect equals that of {}", with)
              : fmt::format("nearly collinear with {} (sine {:.1e}): it would be fitted to noise",
                            with, sine);
      out.push_back(std::move(u));
      leans_on.emplace_back(p, std::move(related));
      continue;
    }
    basis.conservativeResize(Eigen::NoChange, basis.cols() + 1);
    basis.col(basis.cols() - 1) = v / sine;
    accepted.push_back(col);
  }
  std::sort(accepted.begin(), accepted.end());  // reported in model order
  return accepted;
}

// The parameters the design `A` (whitened, a column per model parameter) determines: judged in
// model order, except that where columns share a span it goes to the parameter the run can
// measure. A parameter's reach is its column's norm times a size no real sensor's parameter
// reaches (implausible_sigma): how many of its own sigmas it could show at most.
// - A parameter of reach under kPlausibleSigmas is judged after the others.
// - A parameter held as collinear with taken ones whose reach is kReachRatio times theirs has
//   them judged after it instead (and the columns judged again).
// At rest a gyro's scale factor and misalignment act only through the Earth rate (15 deg/h
// times a milliradian), whose up component follows gravity, while a g-sensitivity of 0.01
// (deg/s)/g moves the gyro by 36 deg/h: in model order the scale and misalignment took the span
// of four g-sensitivities on a six-position run.
std::vector<Eigen::Index> identifiable_columns(const Eigen::MatrixXd& A, const Model& model,
                                               const std::vector<bool>& excluded,
                                               const FitOptions& options,
                                               std::vector<Unidentifiable>& out) {
  std::vector<double> reach(model.size());
  std::vector<std::size_t> order, weak;
  for (std::size_t p = 0; p < model.size(); ++p) {
    reach[p] =
        A.col(static_cast<Eigen::Index>(p)).norm() * implausible_sigma(model.parameters()[p].unit);
    (reach[p] < kPlausibleSigmas ? weak : order).push_back(p);
  }
  order.insert(order.end(), weak.begin(), weak.end());
  std::vector<bool> deferred(model.size(), false);
  const std::size_t first_out = out.size();
  for (;;) {
    out.resize(first_out);
    std::vector<std::pair<std::size_t, std::vector<std::size_t>>> leans_on;
    std::vector<Eigen::Index> accepted =
        judge_columns(A, model, order, excluded, options, out, leans_on);
    std::vector<std::size_t> defer;
    for (const auto& [p, related] : leans_on) {
      for (const std::size_t r : related) {
        if (!deferred[r] && reach[r] * kReachRatio < reach[p]) {
          deferred[r] = true;
          defer.push_back(r);
        }
      }
    }
    if (defer.empty()) return accepted;
    // Each deferred parameter goes to the end, in the order it had.
    std::stable_partition(order.begin(), order.end(), [&](std::size_t p) {
      return std::find(defer.begin(), defer.end(), p) == defer.end();
    });
  }
}

}  // namespace

std::vector<double> temperature_plateaus(const std::vector<StepSummary>& steps) {
  std::vector<double> temps;
  for (const auto& s : steps) temps.push_back(s.signals[0]);
  std::sort(temps.begin(), temps.end());
  std::vector<double> plateaus;
  std::size_t start = 0;
  for (std::size_t i = 1; i <= temps.size(); ++i) {
    if (i == temps.size() || temps[i] - temps[i - 1] > kPlateauGapC) {
      double sum = 0.0;
      for (std::size_t k = start; k < i; ++k) sum += temps[k];
      plateaus.push_back(sum / static_cast<double>(i - start));
      start = i;
    }
  }
  return plateaus;
}

std::size_t distinct_temperatures(const std::vector<StepSummary>& steps) {
  std::vector<double> temps;
  for (const auto& s : steps) temps.push_back(s.signals[0]);
  std::sort(temps.begin(), temps.end());
  std::size_t clusters = 0;
  double cluster_start = 0.0;
  for (std::size_t i = 0; i < temps.size(); ++i) {
    if (i == 0 || temps[i] - cluster_start > kPlateauGapC) {
      ++clusters;
      cluster_start = temps[i];
    }
  }
  return clusters;
}

FitResult fit_model(const std::vector<StepSummary>& steps, const Model& model,
                    const NoiseFloor& floor, const FitOptions& options) {
  return fit_model(steps, model, StepNoise::white_only(floor, "white noise only, as asked"),
                   options);
}

FitResult fit_model(const std::vector<StepSummary>& steps, const Model& model,
                    const StepNoise& noise, const FitOptions& options) {
  const std::size_t P = model.size();
  std::vector<int> channels;
  for (int c = 0; c < kChannels; ++c) {
    if (uses_channel(options.rows, c) && !unmeasured(steps, c)) channels.push_back(c);
  }
  const auto S = static_cast<Eigen::Index>(steps.size());
  const auto rows = static_cast<Eigen::Index>(steps.size() * channels.size());
  // Whitened design and observation, channel by channel (rows of one channel are the steps in
  // order): the raw step means times the inverse Cholesky factor of their covariance. With
  // white noise alone that is each row divided by its step-mean sigma.
  Eigen::MatrixXd A(rows, static_cast<Eigen::Index>(P));
  Eigen::VectorXd y(rows);
  std::vector<Vector6d> marginal_sigma(steps.size(), Vector6d::Zero());
  std::vector<bool> gyro_row(static_cast<std::size_t>(rows), false);
  for (std::size_t ci = 0; ci < channels.size(); ++ci) {
    const int c = channels[ci];
    const Eigen::MatrixXd C = noise.covariance(c, steps);
    const Eigen::LLT<Eigen::MatrixXd> llt(C);
    if (llt.info() != Eigen::Success) {
      throw core::InputError("noise model", fmt::format("the covariance of the {} step means is "
                                                        "not positive definite",
                                                        channel_name(c)));
    }
    Eigen::MatrixXd Ac(S, static_cast<Eigen::Index>(P));
    Eigen::VectorXd yc(S);
    for (Eigen::Index i = 0; i < S; ++i) {
      const StepSummary& s = steps[static_cast<std::size_t>(i)];
      yc[i] = s.measured[c] - s.reference[c];
      Ac.row(i) = s.regressors.row(c);
      marginal_sigma[static_cast<std::size_t>(i)][c] = std::sqrt(C(i, i));
    }
    const auto first = static_cast<Eigen::Index>(ci) * S;
    // A model without parameters on these rows leaves Ac empty; Eigen's triangular solve of an
    // empty block still binds a reference to its null data (undefined behaviour; UBSan stops
    // `calstand fit --model earth_rate` on it), and there is nothing to whiten.
    if (Ac.cols() > 0) A.middleRows(first, S) = llt.matrixL().solve(Ac);
    y.segment(first, S) = llt.matrixL().solve(yc);
    for (Eigen::Index i = 0; i < S; ++i) gyro_row[static_cast<std::size_t>(first + i)] = c < kAx;
  }

  FitResult fit;
  fit.model = model.text();
  for (const auto& t : model.terms()) fit.terms.push_back(t.name);
  fit.floor = noise.white;
  fit.noise = noise;
  fit.rows = options.rows;

  // Identifiability: rules first, then columns in model order against the span of the ones
  // accepted before them (Gram-Schmidt on normalised columns, orthogonalised twice). A column
  // the run barely excites (found by the solve below) is taken out and the pass made again: a
  // parameter held as collinear with it is then judged against what is really determined. On a
  // static run gyro_scale.x acts through the Earth rate's up component, which follows gravity:
  // judged first, it held gyro_g_sensitivity.xy at zero and was then dropped itself, leaving
  // that g-sensitivity to no parameter at all.
  std::vector<bool> excluded(P, false);
  std::vector<Unidentifiable> by_rule;
  temperature_rules(model, distinct_temperatures(steps), excluded, by_rule);
  std::vector<Unidentifiable> barely_excited;  // found by the solves, kept across the passes
  const auto identifiable = [&] {
    fit.unidentifiable = by_rule;
    auto accepted = identifiable_columns(A, model, excluded, options, fit.unidentifiable);
    fit.unidentifiable.insert(fit.unidentifiable.end(), barely_excited.begin(),
                              barely_excited.end());
    return accepted;
  };
  std::vector<Eigen::Index> accepted = identifiable();

  // Solve; drop parameters the run barely excites (sigma beyond any real sensor's value) and
  // judge and solve again, until every remaining one is determined.
  Eigen::Index k = 0;
  Eigen::MatrixXd Ak;
  Eigen::VectorXd scale, theta;
  Eigen::MatrixXd cov;
  double chi2 = 0.0;  // of the last solve
  SensorQuality quality;
  Eigen::VectorXd inflation;
  for (;;) {
    k = static_cast<Eigen::Index>(accepted.size());
    if (rows <= k) {
      throw core::InputError("fit", fmt::format("{} determinable parameters need more than {} "
                                                "step-mean rows to judge the fit: the run has "
                                                "too few steps for this model",
                                                k, rows));
    }
    Ak.resize(rows, k);
    scale.resize(k);
    for (Eigen::Index j = 0; j < k; ++j) {
      scale[j] = A.col(accepted[static_cast<std::size_t>(j)]).norm();
      Ak.col(j) = A.col(accepted[static_cast<std::size_t>(j)]) / scale[j];
    }
    theta = Eigen::VectorXd::Zero(k);
    cov = Eigen::MatrixXd::Zero(k, k);
    if (k > 0) {
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(Ak);
      const Eigen::MatrixXd R = qr.matrixQR().topLeftCorner(k, k).triangularView<Eigen::Upper>();
      theta = qr.solve(y);
      const Eigen::MatrixXd Rinv =
          R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(k, k));
      cov = Rinv * Rinv.transpose();
      theta = theta.cwiseQuotient(scale);
      cov = scale.cwiseInverse().asDiagonal() * cov * scale.cwiseInverse().asDiagonal();
    }
    // The sigmas as they will be reported (inflated by a poor fit of their own sensor's rows)
    // decide what is determined.
    const Eigen::VectorXd e = y - (k > 0 ? Eigen::VectorXd(Ak * (theta.cwiseProduct(scale)))
                                         : Eigen::VectorXd::Zero(rows));
    chi2 = e.squaredNorm();
    quality = sensor_quality(e, gyro_row, model, accepted);
    inflation = parameter_inflation(quality, model, accepted, options.inflate_sigma_by_chi2);
    std::vector<Eigen::Index> kept;
    for (Eigen::Index j = 0; j < k; ++j) {
      const auto p = static_cast<std::size_t>(accepted[static_cast<std::size_t>(j)]);
      const ParameterInfo& info = model.parameters()[p];
      const double sigma = std::sqrt(cov(j, j) * inflation[j]);
      const double bound = implausible_sigma(info.unit);
      if (sigma > bound) {
        barely_excited.push_back(
            {info.name,
             fmt::format("the run barely excites it: its sigma would be {:.2g} {} (beyond the "
                         "{:g} {} of any real sensor)",
                         sigma, info.unit, bound, info.unit),
             {}});
        excluded[p] = true;
      } else {
        kept.push_back(accepted[static_cast<std::size_t>(j)]);
      }
    }
    if (kept.size() == accepted.size()) break;
    accepted = identifiable();
  }
  fit.chi2 = chi2;
  fit.dof = static_cast<int>(rows - k);
  fit.chi2_dof = fit.dof > 0 ? fit.chi2 / fit.dof : std::numeric_limits<double>::quiet_NaN();
  fit.chi2_dof_gyro = quality.chi2_dof(0);
  fit.chi2_dof_accel = quality.chi2_dof(1);
  fit.dof_gyro = quality.dof[0];
  fit.dof_accel = quality.dof[1];
  // Each sensor's parameters take their own sensor's inflation; a covariance between a gyro
  // and an accelerometer parameter the geometric mean of the two.
  for (Eigen::Index i = 0; i < k; ++i) {
    for (Eigen::Index j = 0; j < k; ++j) cov(i, j) *= std::sqrt(inflation[i] * inflation[j]);
  }
  fit.covariance = cov;
  fit.values = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(P));
  for (Eigen::Index j = 0; j < k; ++j) {
    const auto p = static_cast<std::size_t>(accepted[static_cast<std::size_t>(j)]);
    fit.values[static_cast<Eigen::Index>(p)] = theta[j];
    fit.parameters.push_back(
        {model.parameters()[p].name, model.parameters()[p].unit, theta[j], std::sqrt(cov(j, j))});
  }

  // Step-mean residuals in physical units.
  double sum_g = 0.0, sum_a = 0.0;
  Vector6d sum_sigma2 = Vector6d::Zero();
  for (const StepSummary& s : steps) {
    StepResidual sr;
    sr.index = s.index;
    sr.label = s.label;
    sr.start_s = s.start_s;
    sr.end_s = s.end_s;
    sr.is_static = s.is_static;
    sr.signals = s.signals;
    sr.sigma = marginal_sigma[static_cast<std::size_t>(&s - steps.data())];
    sr.residual = s.measured - s.reference - s.regressors * fit.values;
    sum_g += sr.residual.head<3>().squaredNorm();
    sum_a += sr.residual.tail<3>().squaredNorm();
    sum_sigma2 += sr.sigma.cwiseProduct(sr.sigma);
    fit.steps.push_back(std::move(sr));
  }
  const double n = static_cast<double>(steps.size());
  fit.residual_rms_gyro_dps = std::sqrt(sum_g / (3.0 * n));
  fit.residual_rms_accel_mps2 = std::sqrt(sum_a / (3.0 * n));
  fit.noise_floor = (sum_sigma2 / n).cwiseSqrt();
  for (const StepSummary& s : steps) {
    if (s.count > 1 && s.duration_s > 0.0) {
      fit.sample_rate_hz =
          std::max(fit.sample_rate_hz, static_cast<double>(s.count - 1) / s.duration_s);
    }
  }
  return fit;
}

bool above_noise(double chi2_dof, int dof) {
  if (!(dof > 0) || !std::isfinite(chi2_dof)) return false;
  const boost::math::chi_squared_distribution<double> dist(dof);
  return chi2_dof * dof > boost::math::quantile(boost::math::complement(dist, 1e-3));
}

nlohmann::json fit_to_json(const FitResult& fit) {
  nlohmann::json j;
  j["model"] = fit.terms;
  j["chi2_dof"] = fit.chi2_dof;
  j["chi2"] = fit.chi2;
  j["dof"] = fit.dof;
  const auto finite_or_null = [](double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
  };
  j["by_sensor"] = {
      {"gyro", {{"chi2_dof", finite_or_null(fit.chi2_dof_gyro)}, {"dof", fit.dof_gyro}}},
      {"accel", {{"chi2_dof", finite_or_null(fit.chi2_dof_accel)}, {"dof", fit.dof_accel}}}};
  j["noise_model"] = step_noise_to_json(fit.noise, fit.sample_rate_hz);
  j["residual_rms"] = {{"gyro", fit.residual_rms_gyro_dps}, {"accel", fit.residual_rms_accel_mps2}};
  j["noise_floor"] = {{"gyro", {fit.noise_floor[0], fit.noise_floor[1], fit.noise_floor[2]}},
                      {"accel", {fit.noise_floor[3], fit.noise_floor[4], fit.noise_floor[5]}}};
  j["parameters"] = nlohmann::json::array();
  for (const auto& p : fit.parameters) {
    j["parameters"].push_back(
        {{"name", p.name}, {"value", p.value}, {"sigma", p.sigma}, {"unit", p.unit}});
  }
  j["unidentifiable"] = nlohmann::json::array();
  for (const auto& u : fit.unidentifiable) {
    j["unidentifiable"].push_back({{"name", u.name}, {"reason", u.reason}, {"related", u.related}});
  }
  j["steps"] = nlohmann::json::array();
  for (const auto& s : fit.steps) {
    const Vector6d z = s.z();
    // The step's mean of every signal, so that a reader (the console, a script) can draw the
    // residual against what it may follow without reading the samples again.
    nlohmann::json signals = nlohmann::json::object();
    for (std::size_t k = 0; k < kSignalCount; ++k) {
      signals[std::string(signal_names()[k])] = finite_or_null(s.signals[k]);
    }
    j["steps"].push_back(
        {{"step", s.index},
         {"label", s.label},
         {"start_s", s.start_s},
         {"end_s", s.end_s},
         {"static", s.is_static},
         {"residual", std::vector<double>(s.residual.data(), s.residual.data() + 6)},
         {"z", std::vector<double>(z.data(), z.data() + 6)},
         {"signals", std::move(signals)}});
  }
  return j;
}

}  // namespace calstand::solver

// Thermal calibration: a weighted polynomial in dT = T - T_ref through per-plateau estimates,
// named after the contract's temperature terms (error-model.md: `*_temp_bias[:N]` adds
// sum_k c_k dT^k, `*_temp_scale` adds 1e-6 d dT w).

#include "solver/thermal.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "core/error.hpp"

namespace calstand::solver {

namespace {

ThermalPolynomial fit_polynomial(const std::vector<ThermalPoint>& points, int order,
                                 const ThermalOptions& options, const std::string& where) {
  if (order < 0) throw core::InputError(where, fmt::format("order {} must be >= 0", order));
  const auto n = static_cast<int>(points.size());
  // An order-N polynomial has N+1 coefficients; with N >= plateaus it would pass through the
  // points with freedom left over, i.e. be fitted to noise (issue 4: refuse, never fit silently).
  if (order >= n) {
    throw core::InputError(where, fmt::format("order {} needs at least {} temperature plateaus, "
                                              "{} given",
                                              order, order + 1, n));
  }
  if (!std::isfinite(options.temperature_ref_c)) {
    throw core::InputError(where, "temperature_ref_c is not finite");
  }
  std::set<double> distinct;
  for (int i = 0; i < n; ++i) {
    const ThermalPoint& p = points[static_cast<std::size_t>(i)];
    if (!std::isfinite(p.temperature_c) || !std::isfinite(p.value) || !std::isfinite(p.sigma)) {
      throw core::InputError(where, fmt::format("plateau {} has a non-finite temperature, value "
                                                "or sigma",
                                                i));
    }
    if (p.sigma <= 0.0) {
      throw core::InputError(where, fmt::format("plateau {} (T = {} degC): sigma {} must be "
                                                "positive",
                                                i, p.temperature_c, p.sigma));
    }
    distinct.insert(p.temperature_c);
  }
  if (static_cast<int>(distinct.size()) <= order) {
    throw core::InputError(where, fmt::format("order {} needs at least {} distinct plateau "
                                              "temperatures, {} given",
                                              order, order + 1, distinct.size()));
  }

  // Powers of dT grow fast (50^3 = 1.25e5): fit in dT / h with h the largest |dT| so the
  // Vandermonde columns are of one size, then undo: c_k = a_k / h^k.
  const int p = order + 1;
  double h = 0.0;
  for (const ThermalPoint& pt : points) {
    h = std::max(h, std::abs(pt.temperature_c - options.temperature_ref_c));
  }
  if (h == 0.0) h = 1.0;
  Eigen::MatrixXd design(n, p);
  Eigen::VectorXd y(n);
  for (int i = 0; i < n; ++i) {
    const ThermalPoint& pt = points[static_cast<std::size_t>(i)];
    const double x = (pt.temperature_c - options.temperature_ref_c) / h;
    double power = 1.0;
    for (int k = 0; k < p; ++k) {
      design(i, k) = power / pt.sigma;  // weighted rows: 1/sigma
      power *= x;
    }
    y(i) = pt.value / pt.sigma;
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
  const Eigen::VectorXd a = qr.solve(y);
  // (D^T D)^-1 from R: with D P = Q R, (D^T D)^-1 = P R^-1 R^-T P^T.
  const Eigen::MatrixXd R_inv =
      qr.matrixR().topLeftCorner(p, p).triangularView<Eigen::Upper>().solve(
          Eigen::MatrixXd::Identity(p, p));
  const Eigen::MatrixXd cov_a =
      qr.colsPermutation() * (R_inv * R_inv.transpose()) * qr.colsPermutation().transpose();

  ThermalPolynomial r;
  r.temperature_ref_c = options.temperature_ref_c;
  r.order = order;
  r.dof = n - p;
  r.coefficients.resize(p);
  r.covariance.resize(p, p);
  for (int k = 0; k < p; ++k) {
    r.coefficients(k) = a(k) / std::pow(h, k);
    for (int l = 0; l < p; ++l) r.covariance(k, l) = cov_a(k, l) / std::pow(h, k + l);
  }
  r.residuals.resize(n);
  double chi2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const ThermalPoint& pt = points[static_cast<std::size_t>(i)];
    r.residuals(i) = pt.value - r.evaluate(pt.temperature_c);
    chi2 += (r.residuals(i) / pt.sigma) * (r.residuals(i) / pt.sigma);
  }
  r.chi2_dof = r.dof > 0 ? chi2 / r.dof : 0.0;
  if (options.scale_by_chi2 && r.dof > 0 && r.chi2_dof > 1.0) {
    r.covariance *= r.chi2_dof;
    r.scaled_by_chi2 = true;
  }
  r.sigmas = r.covariance.diagonal().cwiseSqrt();
  return r;
}

// "gyro" / "accel", quantity "bias" / "scale", axis "x".."z" of a contract name, or false.
bool split_name(const std::string& name, std::string& sensor, std::string& quantity,
                std::string& axis) {
  const auto dot = name.find('.');
  if (dot == std::string::npos) return false;
  const std::string term = name.substr(0, dot);
  axis = name.substr(dot + 1);
  if (axis != "x" && axis != "y" && axis != "z") return false;
  for (const char* s : {"gyro", "accel"}) {
    for (const char* q : {"bias", "scale"}) {
      if (term == std::string(s) + "_" + q) {
        sensor = s;
        quantity = q;
        return true;
      }
    }
  }
  return false;
}

std::string power_unit(const std::string& base, int k) {
  if (k == 0) return base;
  if (k == 1) return base + "/degC";
  return fmt::format("{}/degC^{}", base, k);
}

}  // namespace

double ThermalPolynomial::evaluate(double temperature_c) const {
  // Horner in dT.
  const double dT = temperature_c - temperature_ref_c;
  double v = 0.0;
  for (Eigen::Index k = coefficients.size() - 1; k >= 0; --k) v = v * dT + coefficients(k);
  return v;
}

ThermalPolynomial thermal_polynomial(const std::vector<ThermalPoint>& points, int order,
                                     const ThermalOptions& options) {
  return fit_polynomial(points, order, options, "thermal_polynomial");
}

std::vector<ClassicalEstimate> thermal_calibration(const std::vector<ThermalPlateau>& plateaus,
                                                   int order, const ThermalOptions& options) {
  constexpr const char* kWhere = "thermal_calibration";
  // Parameters in order of first appearance, so the output follows the caller's order.
  std::vector<std::string> names;
  for (const ThermalPlateau& pl : plateaus) {
    for (const ClassicalEstimate& e : pl.parameters) {
      if (std::find(names.begin(), names.end(), e.name) == names.end()) names.push_back(e.name);
    }
  }
  std::vector<ClassicalEstimate> out;
  for (const std::string& name : names) {
    std::string sensor;
    std::string quantity;
    std::string axis;
    if (!split_name(name, sensor, quantity, axis)) {
      throw core::InputError(kWhere, fmt::format("{} has no temperature term in the error-model "
                                                 "contract (only <sensor>_bias.<axis> and "
                                                 "<sensor>_scale.<axis> have one)",
                                                 name));
    }
    if (quantity == "scale" && order != 1) {
      throw core::InputError(kWhere, fmt::format("{}: order {} asked, but the contract's "
                                                 "{}_temp_scale is linear (order 1 only)",
                                                 name, order, sensor));
    }
    std::vector<ThermalPoint> points;
    for (const ThermalPlateau& pl : plateaus) {
      const auto it = std::find_if(pl.parameters.begin(), pl.parameters.end(),
                                   [&](const ClassicalEstimate& e) { return e.name == name; });
      if (it == pl.parameters.end()) {
        throw core::InputError(
            kWhere, fmt::format("{} is missing on the plateau at {} degC", name, pl.temperature_c));
      }
      points.push_back({pl.temperature_c, it->value, it->sigma});
    }
    const ThermalPolynomial fit =
        fit_polynomial(points, order, options, std::string(kWhere) + ": " + name);
    const std::string base_unit =
        quantity == "scale" ? "ppm" : (sensor == "gyro" ? "deg/s" : "m/s^2");
    out.push_back({name, fit.coefficients(0), fit.sigmas(0), base_unit});
    for (int k = 1; k <= order; ++k) {
      const std::string full = quantity == "scale"
                                   ? fmt::format("{}_temp_scale.{}", sensor, axis)
                                   : fmt::format("{}_temp_bias.{}{}", sensor, axis, k);
      out.push_back({full, fit.coefficients(k), fit.sigmas(k), power_unit(base_unit, k)});
    }
  }
  return out;
}

}  // namespace calstand::solver

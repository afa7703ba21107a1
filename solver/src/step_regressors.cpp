#include "solver/step_regressors.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/rotation.hpp"
#include "core/site.hpp"
#include "solver/custom_term.hpp"
#include "term_kind.hpp"

namespace calstand::solver {

using detail::TermKind;

/// Where each group of products sits in the sums (-1: the model needs none of it), in the
/// order add() computes them.
struct StepRegressorSums::Layout {
  int rate = -1;         ///< w [deg/s], 3
  int force = -1;        ///< f [m/s^2], 3
  int abs_rate = -1;     ///< |w_i|, 3
  int abs_force = -1;    ///< |f_i|, 3
  int rate_sq = -1;      ///< w_i^2, 3
  int force_sq = -1;     ///< (f_i / g0)^2 [g^2], 3
  int temp_powers = -1;  ///< dT^1 .. dT^temp_order
  int temp_order = 0;
  int temp_rate = -1;      ///< dT w_i, 3
  int temp_force = -1;     ///< dT f_i, 3
  int table_rate_sq = -1;  ///< wt_x^2, wt_y^2, wt_z^2, wt_x wt_y, wt_x wt_z, wt_y wt_z [rad^2/s^2]
  int table_accel = -1;    ///< dwt/dt [rad/s^2], 3
  int tilt_force = -1;     ///< C_BL (f_L x e_k), k = x, y: 6
  int tilt_earth = -1;     ///< C_BL (w_ie_L x e_k), k = x, y: 6
  struct Custom {
    std::unique_ptr<CustomTermEvaluator> evaluator;
    std::array<bool, 3> axes{};
    int first = 0;  ///< its 3 products (one per axis; those it does not act on stay 0)
  };
  std::vector<Custom> customs;
};

namespace {

// The catalogue's units: scale factors and the like in ppm, the accelerometer's quadratic
// term in ppm of g per g^2.
constexpr double kPpm = 1e-6;
constexpr double kG0 = core::kStandardGravity;

/// Index of the product wt_i wt_j in Layout::table_rate_sq.
int table_rate_pair(int i, int j) {
  if (i == j) return i;
  return std::min(i, j) == 0 ? 2 + std::max(i, j) : 5;
}

}  // namespace

StepRegressorSums::StepRegressorSums(const Model& model) : layout_(std::make_unique<Layout>()) {
  Layout& l = *layout_;
  int next = 0;
  const auto claim = [&next](int& slot, int n) {
    if (slot < 0) {
      slot = next;
      next += n;
    }
    return slot;
  };
  // The order of every temperature polynomial first: they share one run of powers.
  for (const ModelTerm& t : model.terms()) {
    if (t.info && detail::term_kind(t.info) == TermKind::kTempBias) {
      l.temp_order = std::max(l.temp_order, t.order);
    }
  }
  const auto& terms = model.terms();
  for (std::size_t ti = 0; ti < terms.size(); ++ti) {
    const ModelTerm& t = terms[ti];
    auto p = static_cast<Eigen::Index>(model.parameter_range(ti).first);
    const auto add = [this](int row, Eigen::Index column, int product, double coefficient) {
      entries_.push_back({row, column, product, coefficient});
    };
    if (!t.info) {
      const CustomTermSpec& c = model.customs()[static_cast<std::size_t>(t.custom)];
      Layout::Custom custom;
      custom.evaluator = std::make_unique<CustomTermEvaluator>(c);
      custom.axes = c.axes;
      custom.first = next;
      next += 3;
      const int row = c.sensor == core::TermSensor::kGyro ? kGx : kAx;
      for (int i = 0; i < 3; ++i) {
        if (c.axes[static_cast<std::size_t>(i)]) add(row + i, p++, custom.first + i, 1.0);
      }
      l.customs.push_back(std::move(custom));
      continue;
    }
    const bool gyro = t.info->sensor == core::TermSensor::kGyro;
    const int row = gyro ? kGx : kAx;
    switch (detail::term_kind(t.info)) {
      case TermKind::kBias:
        for (int i = 0; i < 3; ++i) add(row + i, p + i, -1, 1.0);
        break;
      case TermKind::kScale: {
        const int in = gyro ? claim(l.rate, 3) : claim(l.force, 3);
        for (int i = 0; i < 3; ++i) add(row + i, p + i, in + i, kPpm);
        break;
      }
      case TermKind::kMisalignment: {
        // Components xy xz yx yz zx zy: M[i][j] couples input j into axis i.
        const int in = gyro ? claim(l.rate, 3) : claim(l.force, 3);
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) {
            if (i != j) add(row + i, p++, in + j, 1.0);
          }
        }
        break;
      }
      case TermKind::kAsymmetry: {
        const int in = gyro ? claim(l.abs_rate, 3) : claim(l.abs_force, 3);
        for (int i = 0; i < 3; ++i) add(row + i, p + i, in + i, kPpm);
        break;
      }
      case TermKind::kGyroQuadratic:
        for (int i = 0; i < 3; ++i) add(row + i, p + i, claim(l.rate_sq, 3) + i, kPpm);
        break;
      case TermKind::kAccelQuadratic:
        for (int i = 0; i < 3; ++i) add(row + i, p + i, claim(l.force_sq, 3) + i, kPpm * kG0);
        break;
      case TermKind::kGSensitivity:
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) add(kGx + i, p++, claim(l.force, 3) + j, 1.0 / kG0);
        }
        break;
      case TermKind::kTempBias:
        for (int k = 0; k < t.order; ++k) {
          for (int i = 0; i < 3; ++i)
            add(row + i, p++, claim(l.temp_powers, l.temp_order) + k, 1.0);
        }
        break;
      case TermKind::kTempScale: {
        const int in = gyro ? claim(l.temp_rate, 3) : claim(l.temp_force, 3);
        for (int i = 0; i < 3; ++i) add(row + i, p + i, in + i, kPpm);
        break;
      }
      case TermKind::kLeverArm: {
        // [wt x]^2 + [dwt/dt x] (Model::regressors()): [wt x]^2 = wt wt^T - |wt|^2 I, whose
        // diagonal is minus the squares of the other two rates.
        const int sq = claim(l.table_rate_sq, 6);
        const int alpha = claim(l.table_accel, 3);
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) {
            if (r == c) {
              for (int q = 0; q < 3; ++q) {
                if (q != r) add(kAx + r, p + c, sq + q, -1.0);
              }
            } else {
              add(kAx + r, p + c, sq + table_rate_pair(r, c), 1.0);
              // [a x](r, c) = -e_rck a_k: -a_k for (r, c, k) cyclic in (x, y, z), else +a_k.
              const int k = 3 - r - c;
              add(kAx + r, p + c, alpha + k, (c - r + 3) % 3 == 2 ? 1.0 : -1.0);
            }
          }
        }
        break;
      }
      case TermKind::kTilt: {
        const int tf = claim(l.tilt_force, 6);
        const int te = model.earth_rate() ? claim(l.tilt_earth, 6) : -1;
        for (int k = 0; k < 2; ++k) {
          for (int i = 0; i < 3; ++i) {
            add(kAx + i, p + k, tf + 3 * k + i, 1.0);
            if (te >= 0) add(kGx + i, p + k, te + 3 * k + i, 1.0);
          }
        }
        break;
      }
      case TermKind::kNoParameters:  // earth_rate: it changes the reference (SignalBuilder)
        break;
    }
  }
  sums_.assign(static_cast<std::size_t>(next), 0.0);
}

StepRegressorSums::~StepRegressorSums() = default;

void StepRegressorSums::clear() { std::fill(sums_.begin(), sums_.end(), 0.0); }

void StepRegressorSums::add(const Signals& s) {
  const Layout& l = *layout_;
  double* sum = sums_.data();
  const Eigen::Vector3d& w = s.rate_dps;
  const Eigen::Vector3d& f = s.force_mps2;
  if (l.rate >= 0) {
    for (int i = 0; i < 3; ++i) sum[l.rate + i] += w[i];
  }
  if (l.force >= 0) {
    for (int i = 0; i < 3; ++i) sum[l.force + i] += f[i];
  }
  if (l.abs_rate >= 0) {
    for (int i = 0; i < 3; ++i) sum[l.abs_rate + i] += std::abs(w[i]);
  }
  if (l.abs_force >= 0) {
    for (int i = 0; i < 3; ++i) sum[l.abs_force + i] += std::abs(f[i]);
  }
  if (l.rate_sq >= 0) {
    for (int i = 0; i < 3; ++i) sum[l.rate_sq + i] += w[i] * w[i];
  }
  if (l.force_sq >= 0) {
    for (int i = 0; i < 3; ++i) sum[l.force_sq + i] += (f[i] / kG0) * (f[i] / kG0);
  }
  if (l.temp_powers >= 0) {
    double power = 1.0;
    for (int k = 0; k < l.temp_order; ++k) {
      power *= s.dT_c;
      sum[l.temp_powers + k] += power;
    }
  }
  if (l.temp_rate >= 0) {
    for (int i = 0; i < 3; ++i) sum[l.temp_rate + i] += s.dT_c * w[i];
  }
  if (l.temp_force >= 0) {
    for (int i = 0; i < 3; ++i) sum[l.temp_force + i] += s.dT_c * f[i];
  }
  if (l.table_rate_sq >= 0) {
    const Eigen::Vector3d wt = s.table_rate_dps * core::kDegToRad;
    double* sq = sum + l.table_rate_sq;
    sq[0] += wt.x() * wt.x();
    sq[1] += wt.y() * wt.y();
    sq[2] += wt.z() * wt.z();
    sq[3] += wt.x() * wt.y();
    sq[4] += wt.x() * wt.z();
    sq[5] += wt.y() * wt.z();
  }
  if (l.table_accel >= 0) {
    const Eigen::Vector3d alpha = s.table_accel_dps2 * core::kDegToRad;
    for (int i = 0; i < 3; ++i) sum[l.table_accel + i] += alpha[i];
  }
  if (l.tilt_force >= 0 || l.tilt_earth >= 0) {
    // f = C_BL (I - [t x]) f_L, so df/dt_k = C_BL (f_L x e_k); the Earth rate turns likewise.
    const Eigen::Vector3d f_L = s.C_BL.transpose() * f;
    const Eigen::Vector3d w_L = s.C_BL.transpose() * s.earth_rate_dps;
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d e = Eigen::Vector3d::Unit(k);
      if (l.tilt_force >= 0) {
        const Eigen::Vector3d column = s.C_BL * f_L.cross(e);
        for (int i = 0; i < 3; ++i) sum[l.tilt_force + 3 * k + i] += column[i];
      }
      if (l.tilt_earth >= 0) {
        const Eigen::Vector3d column = s.C_BL * w_L.cross(e);
        for (int i = 0; i < 3; ++i) sum[l.tilt_earth + 3 * k + i] += column[i];
      }
    }
  }
  for (const Layout::Custom& c : l.customs) {
    const Eigen::Vector3d e = (*c.evaluator)(s);
    for (int i = 0; i < 3; ++i) {
      if (c.axes[static_cast<std::size_t>(i)]) sum[c.first + i] += e[i];
    }
  }
}

void StepRegressorSums::mean(std::int64_t count, Eigen::Ref<Eigen::MatrixXd> out) const {
  out.setZero();
  const double inv_n = 1.0 / static_cast<double>(count);
  for (const Entry& e : entries_) {
    out(e.row, e.column) +=
        e.product < 0 ? e.coefficient
                      : e.coefficient * (sums_[static_cast<std::size_t>(e.product)] * inv_n);
  }
}

}  // namespace calstand::solver

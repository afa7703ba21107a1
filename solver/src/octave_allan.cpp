#include "solver/octave_allan.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <optional>

namespace calstand::solver {
namespace {

// The octaves of one step end at a tenth of it: the longest blocks still give nine differences.
constexpr std::int64_t kBlocksInLongestOctave = 10;
// Pooled differences an octave needs to enter the fit (its Allan variance then has a relative
// standard error of at most 1/2).
constexpr std::int64_t kMinPooledDifferences = 8;
// The fit needs this many octaves, one more than its two smallest models' parameters.
constexpr int kMinFitOctaves = 3;

/// Basis functions of m AVAR(m) beside the white constant: d / m, c1 m, c2 m^2.
constexpr int kSlowerTerms = 3;

double basis(int term, double m) {
  switch (term) {
    case 0:
      return 1.0 / m;
    case 1:
      return m;
    default:
      return m * m;
  }
}

/// One channel's white variance from its points (block length m, m AVAR(m), standard error):
/// of the models q + any subset of {d / m, c1 m, c2 m^2} that the points can determine, the
/// one with the smallest weighted residual among those with q > 0, d <= 0, c1 >= 0 and c2 >= 0
/// (the sign-constrained least-squares solution). d is an output filter's deficit alone: a
/// positive d would take the concave foot of a band-limited flicker for quantization noise and
/// halve the white part (an ADIS16488-class accelerometer's), where quantization left in q only
/// makes the white part a little larger than it is.
std::optional<double> fit_white(const std::vector<double>& m, const std::vector<double>& e,
                                const std::vector<double>& se) {
  const auto n = static_cast<Eigen::Index>(m.size());
  std::optional<double> best;
  double best_residual = std::numeric_limits<double>::infinity();
  for (unsigned subset = 0; subset < (1u << kSlowerTerms); ++subset) {
    const int parameters = 1 + std::popcount(subset);
    if (n < parameters + 1) continue;
    Eigen::MatrixXd X(n, parameters);
    Eigen::VectorXd y(n);
    std::vector<int> terms;
    for (int t = 0; t < kSlowerTerms; ++t)
      if (subset & (1u << t)) terms.push_back(t);
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      X(i, 0) = 1.0 / se[k];
      for (std::size_t t = 0; t < terms.size(); ++t) {
        X(i, static_cast<Eigen::Index>(t) + 1) = basis(terms[t], m[k]) / se[k];
      }
      y[i] = e[k] / se[k];
    }
    // Columns scaled to unit norm: m^2 spans ten orders of magnitude across the octaves.
    const Eigen::VectorXd norms = X.colwise().norm().transpose();
    Eigen::MatrixXd normalised = X;
    for (Eigen::Index k = 0; k < X.cols(); ++k) normalised.col(k) /= norms[k];
    const Eigen::VectorXd scaled = normalised.colPivHouseholderQr().solve(y);
    const Eigen::VectorXd coefficients = scaled.cwiseQuotient(norms);
    bool feasible = coefficients[0] > 0.0;
    for (std::size_t t = 0; t < terms.size(); ++t) {
      const double coefficient = coefficients[static_cast<Eigen::Index>(t) + 1];
      if (terms[t] == 0 ? coefficient > 0.0 : coefficient < 0.0) feasible = false;
    }
    if (!feasible) continue;
    const double residual = (y - X * coefficients).squaredNorm();
    if (residual < best_residual) {
      best_residual = residual;
      best = coefficients[0];
    }
  }
  return best;
}

}  // namespace

OctaveAllanSums::OctaveAllanSums(int octaves)
    : octaves_(static_cast<std::size_t>(std::max(octaves, 0))) {}

void OctaveAllanSums::push(std::size_t octave, const Vector6d& block_mean) {
  if (octave >= octaves_.size()) return;
  Octave& o = octaves_[octave];
  if (o.has_previous) {
    const Vector6d d = block_mean - o.previous;
    o.sums.half_squared_differences += 0.5 * d.cwiseProduct(d);
    ++o.sums.differences;
  }
  o.previous = block_mean;
  o.has_previous = true;
  if (!o.has_first_half) {
    o.first_half = block_mean;
    o.has_first_half = true;
    return;
  }
  o.has_first_half = false;
  push(octave + 1, 0.5 * (o.first_half + block_mean));
}

std::vector<OctaveAllan> OctaveAllanSums::result() const {
  std::vector<OctaveAllan> out;
  out.reserve(octaves_.size());
  for (const Octave& o : octaves_) out.push_back(o.sums);
  return out;
}

int octaves_for(std::int64_t samples) {
  int octaves = 0;
  while ((std::int64_t{1} << octaves) * kBlocksInLongestOctave <= samples) ++octaves;
  return octaves;
}

std::optional<Vector6d> white_variance_from_octaves(const std::vector<OctaveAllan>& pooled,
                                                    std::int64_t longest_block_samples) {
  std::vector<std::size_t> used;
  for (std::size_t j = 0; j < pooled.size(); ++j) {
    const std::int64_t m = std::int64_t{1} << j;
    if (m < kWhiteFitShortestBlockSamples || m > longest_block_samples) continue;
    if (pooled[j].differences < kMinPooledDifferences) continue;
    used.push_back(j);
  }
  if (static_cast<int>(used.size()) < kMinFitOctaves) return std::nullopt;
  Vector6d white = Vector6d::Zero();
  for (int c = 0; c < kChannels; ++c) {
    std::vector<double> m, e, se;
    for (std::size_t j : used) {
      const double block = std::ldexp(1.0, static_cast<int>(j));
      const double k = static_cast<double>(pooled[j].differences);
      const double tau_avar = block * pooled[j].half_squared_differences[c] / k;
      m.push_back(block);
      e.push_back(tau_avar);
      // The Allan variance of k differences has a relative standard error of about sqrt(2 / k).
      se.push_back(std::max(tau_avar, std::numeric_limits<double>::min()) * std::sqrt(2.0 / k));
    }
    const std::optional<double> q = fit_white(m, e, se);
    if (!q) {
      // No model with a positive white part (a channel without scatter, or one whose curve
      // falls faster than white noise): the shortest usable block's figure, as before.
      white[c] = e.front();
      continue;
    }
    white[c] = *q;
  }
  return white;
}

}  // namespace calstand::solver

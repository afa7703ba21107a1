// Table angles for a body axis up: the search behind `move` steps given as `"up": "+x"`.
#include "procedures/pointing.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace calstand::procedures {
namespace {

// C_LB^T Up within this of the wanted unit vector counts as pointing it (exact multiples of 45
// deg give errors of 1e-16; a mount a few microradians off gives more, and is not "up").
constexpr double kPointingTolerance = 1e-6;

// Candidate (outer, inner) pairs on a grid of `step_deg`, the smallest total move first.
std::vector<std::pair<double, double>> candidates(double step_deg) {
  std::vector<std::pair<double, double>> pairs;
  for (double outer = -180.0 + step_deg; outer <= 180.0; outer += step_deg) {
    for (double inner = -180.0 + step_deg; inner <= 180.0; inner += step_deg) {
      pairs.emplace_back(outer, inner);
    }
  }
  std::stable_sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
    return std::abs(a.first) + std::abs(a.second) < std::abs(b.first) + std::abs(b.second);
  });
  return pairs;
}

}  // namespace

std::string BodyDirection::text() const {
  return std::string(1, sign > 0 ? '+' : '-') + static_cast<char>('x' + axis);
}

std::optional<BodyDirection> parse_body_direction(std::string_view text) {
  if (text.size() != 2 || (text[0] != '+' && text[0] != '-')) return std::nullopt;
  if (text[1] < 'x' || text[1] > 'z') return std::nullopt;
  return BodyDirection{text[1] - 'x', text[0] == '+' ? +1 : -1};
}

std::optional<TableAngles> point_up(const core::TableGeometry& geometry, const BodyDirection& up) {
  const Eigen::Vector3d want = up.sign * Eigen::Vector3d::Unit(up.axis);
  for (const double step_deg : {90.0, 45.0}) {
    for (const auto& [outer, inner] : candidates(step_deg)) {
      const Eigen::Vector3d up_in_body =
          geometry.body_to_level(outer, inner).transpose() * Eigen::Vector3d::UnitZ();
      if ((up_in_body - want).norm() < kPointingTolerance) return TableAngles{outer, inner};
    }
  }
  return std::nullopt;
}

}  // namespace calstand::procedures

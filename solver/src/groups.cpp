#include "solver/groups.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace calstand::solver {
namespace {

// A body axis is "up" when the mean force lies within this angle of it (cos 10 deg).
constexpr double kUpCosine = 0.985;
// A step turns when the table rate reaches this [deg/s].
constexpr double kTurningDps = 1e-3;
// A plateau wider than this [degC] is a ramp: its steps are grouped in bands of kRampBandC.
constexpr double kRampSpanC = 2.0 * kPlateauGapC;
constexpr double kRampBandC = 10.0;

std::string axis_name(int i) { return std::string(1, static_cast<char>('x' + i)); }

}  // namespace

std::vector<int> fit_channels(SensorRows rows) {
  std::vector<int> out;
  for (int c = 0; c < kChannels; ++c) {
    if (rows == SensorRows::kGyro && c >= kAx) continue;
    if (rows == SensorRows::kAccel && c < kAx) continue;
    out.push_back(c);
  }
  return out;
}

std::vector<StepConditions> step_conditions(const std::vector<StepSummary>& steps) {
  const std::vector<double> plateaus = temperature_plateaus(steps);
  // Each plateau's span: a ramp recorded step after step is one plateau tens of degrees wide,
  // whose steps are grouped by temperature band instead of all under its mean.
  std::vector<std::pair<double, double>> spans(plateaus.size(), {1e300, -1e300});
  const auto nearest_plateau = [&](double t) {
    std::size_t best = 0;
    for (std::size_t p = 1; p < plateaus.size(); ++p) {
      if (std::abs(plateaus[p] - t) < std::abs(plateaus[best] - t)) best = p;
    }
    return best;
  };
  for (const auto& s : steps) {
    auto& [lo, hi] = spans[nearest_plateau(s.signals[0])];
    lo = std::min(lo, s.signals[0]);
    hi = std::max(hi, s.signals[0]);
  }
  double t_first = 0.0, t_last = 0.0;
  if (!steps.empty()) {
    t_first = t_last = steps.front().signals[2];
    for (const auto& s : steps) {
      t_first = std::min(t_first, s.signals[2]);
      t_last = std::max(t_last, s.signals[2]);
    }
  }
  std::vector<StepConditions> out;
  for (const StepSummary& s : steps) {
    StepConditions c;
    const std::size_t p = nearest_plateau(s.signals[0]);
    if (spans[p].second - spans[p].first <= kRampSpanC) {
      c.plateau = fmt::format("T {:.0f} degC", plateaus[p]);
    } else {
      const double band_lo = kRampBandC * std::floor(s.signals[0] / kRampBandC);
      c.plateau = fmt::format("T {:.0f}..{:.0f} degC", band_lo, band_lo + kRampBandC);
    }
    const Eigen::Vector3d force(s.signals[6], s.signals[7], s.signals[8]);
    c.orientation = "turning";
    if (force.norm() > 0.0) {
      Eigen::Index i = 0;
      force.cwiseAbs().maxCoeff(&i);
      if (std::abs(force[i]) / force.norm() >= kUpCosine && force.norm() > 0.5 * 9.8) {
        c.orientation =
            fmt::format("{}{} up", force[i] > 0.0 ? "+" : "-", axis_name(static_cast<int>(i)));
      }
    }
    const Eigen::Vector3d rate(s.signals[9], s.signals[10], s.signals[11]);
    if (rate.norm() < kTurningDps) {
      c.rate = c.direction = c.axis = "static";
    } else {
      Eigen::Index i = 0;
      rate.cwiseAbs().maxCoeff(&i);
      c.rate = fmt::format("|w| {:.3g} deg/s", rate.norm());
      c.axis = "about body " + axis_name(static_cast<int>(i));
      c.direction = rate[i] > 0.0 ? "positive (CCW) turn" : "negative (CW) turn";
    }
    const double span = t_last - t_first;
    const int quarter =
        span > 0.0 ? std::min(3, static_cast<int>(4.0 * (s.signals[2] - t_first) / span)) : 0;
    static const char* kQuarters[4] = {"1st", "2nd", "3rd", "4th"};
    c.time = fmt::format("run {} quarter", kQuarters[quarter]);
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<GroupQuality> group_quality(const FitResult& fit,
                                        const std::vector<StepSummary>& steps) {
  const std::vector<StepConditions> conditions = step_conditions(steps);
  const std::vector<int> channels = fit_channels(fit.rows);
  struct Acc {
    double chi2 = 0.0;
    std::size_t rows = 0;
    std::vector<std::size_t> steps;
  };
  std::map<std::string, Acc> groups;
  for (std::size_t k = 0; k < steps.size() && k < fit.steps.size(); ++k) {
    const Vector6d z = fit.steps[k].z();
    double chi2 = 0.0;
    for (int c : channels) chi2 += z[c] * z[c];
    const StepConditions& c = conditions[k];
    for (const std::string& g :
         {"plateau: " + c.plateau, "orientation: " + c.orientation, "rate: " + c.rate,
          "direction: " + c.direction, "axis: " + c.axis, "time: " + c.time}) {
      Acc& a = groups[g];
      a.chi2 += chi2;
      a.rows += channels.size();
      a.steps.push_back(fit.steps[k].index);
    }
  }
  std::vector<GroupQuality> out;
  for (auto& [name, a] : groups) {
    if (a.steps.size() == steps.size()) continue;
    out.push_back({name, a.chi2 / static_cast<double>(a.rows), std::move(a.steps)});
  }
  std::stable_sort(out.begin(), out.end(), [](const GroupQuality& a, const GroupQuality& b) {
    return a.chi2_dof > b.chi2_dof;
  });
  return out;
}

std::vector<WorstStep> worst_steps(const FitResult& fit, std::size_t count) {
  std::vector<WorstStep> all;
  for (const auto& s : fit.steps) {
    const Vector6d z = s.z();
    for (int c : fit_channels(fit.rows))
      all.push_back({s.index, std::string(channel_name(c)), z[c]});
  }
  std::sort(all.begin(), all.end(),
            [](const WorstStep& a, const WorstStep& b) { return std::abs(a.z) > std::abs(b.z); });
  if (all.size() > count) all.resize(count);
  return all;
}

void add_groups_json(nlohmann::json& j, const std::vector<GroupQuality>& groups,
                     const std::vector<WorstStep>& worst) {
  j["groups"] = nlohmann::json::array();
  for (const auto& g : groups) {
    j["groups"].push_back({{"group", g.group}, {"chi2_dof", g.chi2_dof}, {"steps", g.steps}});
  }
  j["worst_steps"] = nlohmann::json::array();
  for (const auto& w : worst) {
    j["worst_steps"].push_back({{"step", w.step}, {"channel", w.channel}, {"z", w.z}});
  }
}

}  // namespace calstand::solver

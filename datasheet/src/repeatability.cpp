#include "datasheet/repeatability.hpp"

#include <fmt/format.h>

#include <Eigen/Core>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <map>
#include <optional>

#include "core/error.hpp"
#include "core/table_geometry.hpp"
#include "datasheet_units.hpp"
#include "solver/run_setup.hpp"
#include "store/run_store.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {
namespace {

/// Blocks a capture is cut into to estimate the noise of its mean from inside it (batch means):
/// enough blocks for a variance, long enough blocks to hold the noise's correlation.
constexpr std::size_t kBlocks = 10;

struct CaptureMean {
  std::array<double, 6> mean{};
  std::array<double, 6> variance_of_mean{};  ///< from the block means
  std::size_t samples = 0;
};

/// One rate step reduced to what a scale estimate needs.
struct TurnMean {
  int axis = 0;                ///< body axis turned about: 0, 1, 2
  double body_rate_dps = 0.0;  ///< mean table rate about it, signed [deg/s]
  double gyro_mean_dps = 0.0;  ///< mean of that axis's gyro [deg/s]
  std::size_t samples = 0;
};

/// A turn's two directions at one rate magnitude in one cycle.
struct TurnPair {
  std::optional<TurnMean> plus, minus;
};

/// (body axis, rate magnitude in mdeg/s): the rates of one procedure are equal in every cycle.
using TurnKey = std::pair<int, long long>;

double channel_value(const core::ImuSample& s, std::size_t c) {
  return c < 3 ? s.gyro_dps[static_cast<int>(c)] : s.accel_mps2[static_cast<int>(c - 3)];
}

CaptureMean capture_mean(const store::StepData& step) {
  CaptureMean out;
  const std::size_t n = step.samples.size();
  const std::size_t per_block = n / kBlocks;
  for (std::size_t c = 0; c < 6; ++c) {
    double sum = 0.0;
    for (const auto& s : step.samples) sum += channel_value(s, c);
    out.mean[c] = sum / static_cast<double>(n);
    if (per_block < 2) continue;
    double ss = 0.0;
    for (std::size_t b = 0; b < kBlocks; ++b) {
      double block = 0.0;
      for (std::size_t i = b * per_block; i < (b + 1) * per_block; ++i) {
        block += channel_value(step.samples[i], c);
      }
      const double d = block / static_cast<double>(per_block) - out.mean[c];
      ss += d * d;
    }
    out.variance_of_mean[c] = ss / static_cast<double>(kBlocks - 1) / static_cast<double>(kBlocks);
  }
  out.samples = n;
  return out;
}

/// The body rate of a rate step from its encoder state at each sample (station geometry and
/// mount); none for a step without a known orientation.
std::optional<TurnMean> turn_mean(const store::StepData& step, const core::TableGeometry& g) {
  if (step.samples.size() < 2 || step.table.size() != step.samples.size()) return std::nullopt;
  Eigen::Vector3d rate_sum = Eigen::Vector3d::Zero();
  for (const store::TableSample& t : step.table) {
    if (!std::isfinite(t.outer_deg) || !std::isfinite(t.inner_deg)) return std::nullopt;
    const Eigen::Vector3d level =
        g.table_rate_level_dps(t.outer_deg, t.outer_rate_dps, t.inner_rate_dps);
    rate_sum += g.body_to_level(t.outer_deg, t.inner_deg).transpose() * level;
  }
  const Eigen::Vector3d rate = rate_sum / static_cast<double>(step.table.size());
  TurnMean out;
  rate.cwiseAbs().maxCoeff(&out.axis);
  out.body_rate_dps = rate[out.axis];
  double sum = 0.0;
  for (const auto& s : step.samples) sum += s.gyro_dps[out.axis];
  out.samples = step.samples.size();
  out.gyro_mean_dps = sum / static_cast<double>(out.samples);
  return out;
}

/// One cycle's record: its static captures in order, its turns by axis and rate.
struct Cycle {
  std::vector<CaptureMean> captures;
  std::map<TurnKey, TurnPair> turns;
};

/// sqrt(spread^2 - noise^2) of a spread over `dof` degrees of freedom, and its interval from
/// the chi-square distribution of the spread, in the unit `k` converts to.
struct UnitPart {
  double value = 0.0, lo = 0.0, hi = 0.0;
};
UnitPart unit_part(double spread_sq, double noise_sq, int dof, double confidence, double k) {
  const boost::math::chi_squared chi2(dof);
  const double alpha = 1.0 - confidence;
  const double q_hi = boost::math::quantile(chi2, 1.0 - alpha / 2.0);
  const double q_lo = boost::math::quantile(chi2, alpha / 2.0);
  // The spread holds the measurement noise of each estimate too; what is left is the unit's.
  const auto part = [&](double s2) { return k * std::sqrt(std::max(0.0, s2 - noise_sq)); };
  return {part(spread_sq), part(spread_sq * dof / q_hi), part(spread_sq * dof / q_lo)};
}

/// The gyro scale-factor repeatability about each body axis from the cycles' turn pairs.
void scale_repeatability(const std::map<long long, Cycle>& cycles, const std::string& where,
                         RepeatabilityAnalysis& out) {
  const Cycle& first = cycles.begin()->second;
  for (const auto& [key, pair] : first.turns) {
    if (!pair.plus || !pair.minus) continue;
    ScaleRepeatability& axis = out.gyro_scale[static_cast<std::size_t>(key.first)];
    axis.measured = true;
    axis.rates_dps.push_back(static_cast<double>(key.second) / 1000.0);
  }
  for (std::size_t a = 0; a < 3; ++a) {
    ScaleRepeatability& axis = out.gyro_scale[a];
    if (!axis.measured) continue;
    double ss = 0.0, noise_sq = 0.0;
    for (std::size_t r = 0; r < axis.rates_dps.size(); ++r) {
      const TurnKey key{static_cast<int>(a), std::llround(axis.rates_dps[r] * 1000.0)};
      std::vector<double> scale_ppm;
      for (const auto& [number, cycle] : cycles) {
        const auto found = cycle.turns.find(key);
        if (found == cycle.turns.end() || !found->second.plus || !found->second.minus) {
          throw core::InputError(
              where, fmt::format("cycle {} has no turn both ways about body {} at {:g} deg/s, "
                                 "cycle {} has: the cycles must repeat the same turns",
                                 number, "xyz"[a], axis.rates_dps[r], cycles.begin()->first));
        }
        const TurnMean& plus = *found->second.plus;
        const TurnMean& minus = *found->second.minus;
        const double span_dps = plus.body_rate_dps - minus.body_rate_dps;
        scale_ppm.push_back(1e6 * ((plus.gyro_mean_dps - minus.gyro_mean_dps) / span_dps - 1.0));
        // White noise of the two means, from the cycle's static capture: the variance of a
        // mean falls with its sample count.
        const CaptureMean& still = cycle.captures.front();
        const double per_sample = still.variance_of_mean[a] * static_cast<double>(still.samples);
        noise_sq +=
            1e12 * per_sample *
            (1.0 / static_cast<double>(plus.samples) + 1.0 / static_cast<double>(minus.samples)) /
            (span_dps * span_dps);
      }
      double mean = 0.0;
      for (double s : scale_ppm) mean += s / static_cast<double>(scale_ppm.size());
      for (double s : scale_ppm) {
        ss += (s - mean) * (s - mean);
        if (r == 0) axis.scale_ppm.push_back(s - mean);
      }
    }
    axis.dof = static_cast<int>(axis.rates_dps.size() * (cycles.size() - 1));
    noise_sq /= static_cast<double>(axis.rates_dps.size() * cycles.size());
    const double spread_sq = ss / axis.dof;
    axis.spread_ppm = std::sqrt(spread_sq);
    axis.noise_of_estimates_ppm = std::sqrt(noise_sq);
    const UnitPart part = unit_part(spread_sq, noise_sq, axis.dof, out.confidence, 1.0);
    axis.repeatability_ppm = part.value;
    axis.repeatability_lo_ppm = part.lo;
    axis.repeatability_hi_ppm = part.hi;
  }
}

}  // namespace

RepeatabilityAnalysis analyse_repeatability(store::Database& db, std::int64_t run,
                                            const std::string& device) {
  const std::string where = fmt::format("run {}", run);
  const std::string chosen = store::choose_device(db, run, device);
  store::RunStore runs(db);
  const core::TableGeometry geometry = solver::run_setup(runs.load_run(run), run, chosen).geometry;
  std::map<long long, Cycle> cycles;
  store::for_each_step_data(db, run, chosen, [&](const store::StepData& step) {
    if ((step.step.kind != "capture" && step.step.kind != "rate") || step.samples.size() < 2)
      return;
    const nlohmann::json loops = step.step.commanded.value("loop_values", nlohmann::json::object());
    if (!loops.contains("cycle") || !loops["cycle"].is_number()) return;
    Cycle& cycle = cycles[loops["cycle"].get<long long>()];
    if (step.step.kind == "capture") {
      cycle.captures.push_back(capture_mean(step));
      return;
    }
    const std::optional<TurnMean> turn = turn_mean(step, geometry);
    if (!turn) return;
    TurnPair& pair =
        cycle.turns[{turn->axis, std::llround(std::abs(turn->body_rate_dps) * 1000.0)}];
    (turn->body_rate_dps > 0.0 ? pair.plus : pair.minus) = turn;
  });
  std::erase_if(cycles, [](const auto& c) { return c.second.captures.empty(); });
  if (cycles.size() < 2) {
    throw core::InputError(where, fmt::format("has {} power cycle(s) with captures; the "
                                              "repeatability needs at least two (library "
                                              "procedure repeatability)",
                                              cycles.size()));
  }
  const std::size_t positions = cycles.begin()->second.captures.size();
  for (const auto& [cycle, record] : cycles) {
    const std::vector<CaptureMean>& captures = record.captures;
    if (captures.size() != positions) {
      throw core::InputError(where,
                             fmt::format("cycle {} has {} captures, cycle {} has {}: the "
                                         "cycles must repeat the same positions",
                                         cycle, captures.size(), cycles.begin()->first, positions));
    }
  }
  RepeatabilityAnalysis out;
  out.run = run;
  out.device = chosen;
  out.cycles = cycles.size();
  out.positions = positions;
  out.dof = static_cast<int>(positions * (cycles.size() - 1));
  static constexpr std::array<const char*, 6> kNames = {"gx", "gy", "gz", "ax", "ay", "az"};
  for (std::size_t c = 0; c < 6; ++c) {
    const double k = c < 3 ? kDegPerSToDegPerH : kMps2ToUg;
    ChannelRepeatability& ch = out.channels[c];
    ch.channel = kNames[c];
    double ss = 0.0;
    double noise = 0.0;
    for (std::size_t p = 0; p < positions; ++p) {
      double mean = 0.0;
      for (const auto& [cycle, record] : cycles) {
        mean += record.captures[p].mean[c] / static_cast<double>(out.cycles);
      }
      for (const auto& [cycle, record] : cycles) {
        const double d = record.captures[p].mean[c] - mean;
        ss += d * d;
        noise += record.captures[p].variance_of_mean[c];
        if (p == 0) ch.turn_on_bias.push_back(k * d);
      }
    }
    const double spread_sq = ss / out.dof;
    const double noise_sq = noise / static_cast<double>(positions * out.cycles);
    ch.spread = k * std::sqrt(spread_sq);
    ch.noise_of_means = k * std::sqrt(noise_sq);
    const UnitPart part = unit_part(spread_sq, noise_sq, out.dof, out.confidence, k);
    ch.repeatability = part.value;
    ch.repeatability_lo = part.lo;
    ch.repeatability_hi = part.hi;
  }
  scale_repeatability(cycles, where, out);
  return out;
}

nlohmann::json to_json(const RepeatabilityAnalysis& r) {
  const auto sensor = [&](std::size_t first, const char* unit) {
    nlohmann::json rep = nlohmann::json::array();
    nlohmann::json interval = nlohmann::json::array();
    nlohmann::json spread = nlohmann::json::array();
    nlohmann::json noise = nlohmann::json::array();
    nlohmann::json per_cycle = nlohmann::json::array();
    for (std::size_t c = first; c < first + 3; ++c) {
      const ChannelRepeatability& ch = r.channels[c];
      rep.push_back(ch.repeatability);
      interval.push_back({ch.repeatability_lo, ch.repeatability_hi});
      spread.push_back(ch.spread);
      noise.push_back(ch.noise_of_means);
      per_cycle.push_back(ch.turn_on_bias);
    }
    return nlohmann::json{{fmt::format("bias_repeatability_{}", unit), rep},
                          {fmt::format("interval_{}", unit), interval},
                          {fmt::format("spread_{}", unit), spread},
                          {fmt::format("noise_of_means_{}", unit), noise},
                          {fmt::format("turn_on_bias_{}", unit), per_cycle}};
  };
  nlohmann::json gyro = sensor(0, "deg_per_h");
  const auto scale_entry = [&](const char* key, const auto& value_of) {
    nlohmann::json values = nlohmann::json::array();
    for (const ScaleRepeatability& a : r.gyro_scale) {
      values.push_back(a.measured ? value_of(a) : nlohmann::json(nullptr));
    }
    gyro[key] = values;
  };
  scale_entry("scale_factor_repeatability_ppm",
              [](const ScaleRepeatability& a) { return nlohmann::json(a.repeatability_ppm); });
  scale_entry("scale_interval_ppm", [](const ScaleRepeatability& a) {
    return nlohmann::json::array({a.repeatability_lo_ppm, a.repeatability_hi_ppm});
  });
  scale_entry("scale_spread_ppm",
              [](const ScaleRepeatability& a) { return nlohmann::json(a.spread_ppm); });
  scale_entry("scale_noise_ppm",
              [](const ScaleRepeatability& a) { return nlohmann::json(a.noise_of_estimates_ppm); });
  scale_entry("scale_per_cycle_ppm",
              [](const ScaleRepeatability& a) { return nlohmann::json(a.scale_ppm); });
  scale_entry("scale_rates_dps",
              [](const ScaleRepeatability& a) { return nlohmann::json(a.rates_dps); });
  scale_entry("scale_dof", [](const ScaleRepeatability& a) { return nlohmann::json(a.dof); });
  return {{"run", r.run},       {"device", r.device},
          {"cycles", r.cycles}, {"positions", r.positions},
          {"dof", r.dof},       {"confidence", r.confidence},
          {"gyro", gyro},       {"accel", sensor(3, "ug")}};
}

}  // namespace calstand::analysis

#include "analysis/repeatability.hpp"

#include <fmt/format.h>

#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <map>

#include "core/error.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {
namespace {

constexpr double kDegPerSToDegPerH = 3600.0;
constexpr double kMps2ToUg = 1e6 / 9.80665;
/// Blocks a capture is cut into to estimate the noise of its mean from inside it (batch means):
/// enough blocks for a variance, long enough blocks to hold the noise's correlation.
constexpr std::size_t kBlocks = 10;

struct CaptureMean {
  std::array<double, 6> mean{};
  std::array<double, 6> variance_of_mean{};  ///< from the block means
};

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
  return out;
}

}  // namespace

RepeatabilityAnalysis analyse_repeatability(store::Database& db, std::int64_t run,
                                            const std::string& device) {
  const std::string where = fmt::format("run {}", run);
  const std::string chosen = store::choose_device(db, run, device);
  // cycle -> its captures in order
  std::map<long long, std::vector<CaptureMean>> cycles;
  for (const store::StepData& step : store::read_step_data(db, run, chosen)) {
    if (step.step.kind != "capture" || step.samples.size() < 2) continue;
    const nlohmann::json loops = step.step.commanded.value("loop_values", nlohmann::json::object());
    if (!loops.contains("cycle") || !loops["cycle"].is_number()) continue;
    cycles[loops["cycle"].get<long long>()].push_back(capture_mean(step));
  }
  if (cycles.size() < 2) {
    throw core::InputError(where, fmt::format("has {} power cycle(s) with captures; the "
                                              "repeatability needs at least two (library "
                                              "procedure repeatability)",
                                              cycles.size()));
  }
  const std::size_t positions = cycles.begin()->second.size();
  for (const auto& [cycle, captures] : cycles) {
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
  const boost::math::chi_squared chi2(out.dof);
  const double alpha = 1.0 - out.confidence;
  const double q_hi = boost::math::quantile(chi2, 1.0 - alpha / 2.0);
  const double q_lo = boost::math::quantile(chi2, alpha / 2.0);
  static constexpr std::array<const char*, 6> kNames = {"gx", "gy", "gz", "ax", "ay", "az"};
  for (std::size_t c = 0; c < 6; ++c) {
    const double k = c < 3 ? kDegPerSToDegPerH : kMps2ToUg;
    ChannelRepeatability& ch = out.channels[c];
    ch.channel = kNames[c];
    double ss = 0.0;
    double noise = 0.0;
    for (std::size_t p = 0; p < positions; ++p) {
      double mean = 0.0;
      for (const auto& [cycle, captures] : cycles) mean += captures[p].mean[c] / out.cycles;
      for (const auto& [cycle, captures] : cycles) {
        const double d = captures[p].mean[c] - mean;
        ss += d * d;
        noise += captures[p].variance_of_mean[c];
        if (p == 0) ch.turn_on_bias.push_back(k * d);
      }
    }
    const double spread_sq = ss / out.dof;
    const double noise_sq = noise / static_cast<double>(positions * out.cycles);
    ch.spread = k * std::sqrt(spread_sq);
    ch.noise_of_means = k * std::sqrt(noise_sq);
    // The spread holds the measurement noise of each mean too; what is left is the unit's.
    const auto unit_part = [&](double s2) { return k * std::sqrt(std::max(0.0, s2 - noise_sq)); };
    ch.repeatability = unit_part(spread_sq);
    ch.repeatability_lo = unit_part(spread_sq * out.dof / q_hi);
    ch.repeatability_hi = unit_part(spread_sq * out.dof / q_lo);
  }
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
  return {{"run", r.run},
          {"device", r.device},
          {"cycles", r.cycles},
          {"positions", r.positions},
          {"dof", r.dof},
          {"confidence", r.confidence},
          {"gyro", sensor(0, "deg_per_h")},
          {"accel", sensor(3, "ug")}};
}

}  // namespace calstand::analysis

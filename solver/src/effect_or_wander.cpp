#include "solver/effect_or_wander.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "solver/groups.hpp"
#include "wander_kernels.hpp"

namespace calstand::solver {

struct EffectOrWander::Kernels : detail::WanderKernels {};

EffectOrWander::EffectOrWander(std::vector<StepSummary> rows, const Model& superset,
                               SensorRows sensor_rows, const KnownWander* known)
    : rows_(std::move(rows)),
      superset_(superset),
      sensor_rows_(sensor_rows),
      known_wander_(known != nullptr) {
  white_ = measure_noise_floor(rows_);
  FitOptions fo;
  fo.rows = sensor_rows;
  try {
    const FitResult fit = fit_model(rows_, superset_, white_, fo);
    const auto& all = superset_.parameters();
    for (const FittedParameter& fp : fit.parameters) {
      const auto it = std::find_if(all.begin(), all.end(),
                                   [&](const ParameterInfo& q) { return q.name == fp.name; });
      if (it != all.end()) columns_.push_back(it - all.begin());
    }
  } catch (const core::InputError&) {
    // More catalogue parameters than rows: every column, and the comparison is as weak as the run.
    for (Eigen::Index k = 0; k < static_cast<Eigen::Index>(superset_.size()); ++k) {
      columns_.push_back(k);
    }
  }
  log_rows_ = std::log(static_cast<double>(rows_.size() * fit_channels(sensor_rows).size()));
  auto kernels = std::make_shared<Kernels>();
  if (known) {
    const FlickerBand band = flicker_band(rows_);
    for (const WanderModel& w : known->wander) {
      kernels->wanders.push_back(detail::known_kernel(spread_over(w, band), rows_));
    }
  } else {
    static_cast<detail::WanderKernels&>(*kernels) = detail::make_wander_kernels(rows_);
  }
  kernels_ = std::move(kernels);
}

EffectOrWander::ChannelScore EffectOrWander::score_channel(int channel,
                                                           const std::vector<Eigen::Index>& columns,
                                                           const Eigen::MatrixXd* extra) const {
  const detail::ChannelProblem p =
      detail::channel_problem(rows_, columns, channel, white_.density[channel], extra);
  ChannelScore out;
  out.fixed_parameters = p.parameters;
  if (known_wander_) {
    const detail::Kernel& k = kernels_->wanders[static_cast<std::size_t>(channel)];
    out.log_likelihood = detail::known_log_likelihood(k, p, detail::Likelihood::kProfile);
    out.wander = k.unit;
    return out;
  }
  out.log_likelihood = detail::white_log_likelihood(p, detail::Likelihood::kProfile);
  // A channel's wander is informed by its own rows: its parameters cost ln(rows of the
  // channel) each, as the noise model's choice of process charges them.
  const double log_channel_rows = std::log(static_cast<double>(rows_.size()));
  for (const detail::Kernel& k : kernels_->wanders) {
    const detail::Trial t =
        detail::best_amplitude(k, p, kernels_->typical_count, detail::Likelihood::kProfile);
    if (t.log_likelihood - 0.5 * k.parameters * log_channel_rows >
        out.log_likelihood - 0.5 * out.noise_parameters * log_channel_rows) {
      out.log_likelihood = t.log_likelihood;
      out.noise_parameters = k.parameters;
      out.wander = detail::with_amplitude(k, t.amplitude);
    }
  }
  out.noise_penalty = out.noise_parameters * log_channel_rows;
  return out;
}

Hypothesis EffectOrWander::score(const std::array<bool, kChannels>& channels,
                                 const std::vector<Eigen::Index>& columns,
                                 const std::array<Eigen::MatrixXd, kChannels>* extra,
                                 int nonlinear) const {
  Hypothesis h;
  h.noise = StepNoise::white_only(white_, "");
  h.noise.method =
      "white noise from inside the steps; wandering bias re-estimated under the design";
  h.fixed_parameters = nonlinear;
  double fixed_penalty = 0.0;
  int channels_scored = 0;
  const double log_channel_rows = std::log(static_cast<double>(rows_.size()));
  const bool base_design = !extra && columns == columns_;
  for (int c : fit_channels(sensor_rows_)) {
    const auto uc = static_cast<std::size_t>(c);
    if (!channels[uc]) continue;
    h.scored[uc] = true;
    const Eigen::MatrixXd* more = extra && (*extra)[uc].cols() > 0 ? &(*extra)[uc] : nullptr;
    // The superset alone is the hypothesis every term is compared with: scored once a channel.
    ChannelScore cs;
    if (base_design && base_scores_[uc]) {
      cs = *base_scores_[uc];
    } else {
      cs = score_channel(c, columns, more);
      if (base_design) base_scores_[uc] = cs;
    }
    h.fixed_parameters += cs.fixed_parameters;
    fixed_penalty += cs.fixed_parameters * log_channel_rows;
    ++channels_scored;
    h.log_likelihood += cs.log_likelihood;
    h.noise_parameters += cs.noise_parameters;
    h.noise_penalty += cs.noise_penalty;
    ChannelStepNoise& ch = h.noise.channels[uc];
    ch.determined = true;
    ch.wander = cs.wander;
    ch.note = known_wander_ ? "measured outside the run"
                            : "re-estimated under the design (profile likelihood)";
  }
  // A column acts on one channel and is informed by that channel's rows; a shared time constant
  // by the rows of every channel it spans.
  fixed_penalty +=
      nonlinear * std::log(static_cast<double>(rows_.size() * std::max(channels_scored, 1)));
  h.bic = -2.0 * h.log_likelihood + fixed_penalty + h.noise_penalty;
  return h;
}

Hypothesis EffectOrWander::base(const std::array<bool, kChannels>& channels) const {
  return score(channels, columns_, nullptr, 0);
}

Hypothesis EffectOrWander::with_columns(const std::array<Eigen::MatrixXd, kChannels>& extra,
                                        int nonlinear) const {
  std::array<bool, kChannels> channels{};
  for (int c = 0; c < kChannels; ++c) {
    channels[static_cast<std::size_t>(c)] = extra[static_cast<std::size_t>(c)].cols() > 0;
  }
  return score(channels, columns_, &extra, nonlinear);
}

std::array<bool, kChannels> EffectOrWander::channels_of(
    const std::vector<std::string>& parameters) const {
  std::array<bool, kChannels> out{};
  for (Eigen::Index col : columns_) {
    const std::string& name = superset_.parameters()[static_cast<std::size_t>(col)].name;
    if (std::find(parameters.begin(), parameters.end(), name) == parameters.end()) continue;
    for (int c = 0; c < kChannels; ++c) {
      for (const StepSummary& s : rows_) {
        if (s.regressors(c, col) != 0.0) {
          out[static_cast<std::size_t>(c)] = true;
          break;
        }
      }
    }
  }
  return out;
}

namespace {

std::vector<Eigen::Index> columns_without(const std::vector<Eigen::Index>& columns,
                                          const Model& superset,
                                          const std::vector<std::string>& parameters) {
  std::vector<Eigen::Index> kept;
  for (Eigen::Index col : columns) {
    const std::string& name = superset.parameters()[static_cast<std::size_t>(col)].name;
    if (std::find(parameters.begin(), parameters.end(), name) == parameters.end()) {
      kept.push_back(col);
    }
  }
  return kept;
}

}  // namespace

Hypothesis EffectOrWander::without(const std::vector<std::string>& parameters,
                                   const std::array<Eigen::MatrixXd, kChannels>& extra,
                                   int nonlinear) const {
  return score(channels_of(parameters), columns_without(columns_, superset_, parameters), &extra,
               nonlinear);
}

Hypothesis EffectOrWander::with_columns_on(const std::array<bool, kChannels>& channels,
                                           const std::array<Eigen::MatrixXd, kChannels>& extra,
                                           int nonlinear) const {
  return score(channels, columns_, &extra, nonlinear);
}

Hypothesis EffectOrWander::without(const std::vector<std::string>& parameters) const {
  return score(channels_of(parameters), columns_without(columns_, superset_, parameters), nullptr,
               0);
}

}  // namespace calstand::solver

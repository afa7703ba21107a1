// The noise figures from the identified model where the record supports it, else the Allan
// line's, each naming its estimator.
#include "noise/model_figures.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

#include "core/error.hpp"
#include "store/sample_reader.hpp"

namespace calstand::solver {
namespace {

/// The two-sided 95 % normal quantile, for the Allan line's value +- 1.96 sigma.
constexpr double kZ95 = 1.959963984540054;

ModelFigure from_model(const char* name, double value, double lo, double hi, std::string unit) {
  ModelFigure f;
  f.name = name;
  f.value = value;
  f.lo = lo;
  f.hi = hi;
  f.unit = std::move(unit);
  f.estimator = std::string(kGmwmEstimator);
  return f;
}

ModelFigure from_allan_line(const char* name, const NoiseTerm& t, std::string unit,
                            std::string note) {
  ModelFigure f;
  f.name = name;
  f.value = t.value;
  f.lo = std::max(0.0, t.value - kZ95 * t.sigma);
  f.hi = t.value + kZ95 * t.sigma;
  f.unit = std::move(unit);
  f.estimator = std::string(kAllanLineEstimator);
  f.resolved = t.resolved;
  f.note = std::move(note);
  return f;
}

}  // namespace

std::vector<ModelFigure> model_figures(const std::optional<NoiseModel>& model,
                                       const NoiseTerms& allan, const std::string& unit,
                                       const std::string& why_none) {
  const auto term = [&](NoiseKind kind) -> const NoiseModelTerm* {
    if (!model) return nullptr;
    for (const NoiseModelTerm& t : model->terms) {
      if (t.kind == kind) return &t;
    }
    return nullptr;
  };
  // Why a figure comes from the Allan line: no model, or a model without the term.
  const auto why = [&](const char* term_name) {
    return model ? fmt::format("the identified model has no {} term", term_name) : why_none;
  };
  std::vector<ModelFigure> out;
  if (const NoiseModelTerm* w = term(NoiseKind::kWhite)) {
    out.push_back(
        from_model("white_density", w->value, w->value_lo, w->value_hi, unit + "/sqrt(Hz)"));
  } else {
    out.push_back(
        from_allan_line("white_density", allan.random_walk, unit + "/sqrt(Hz)", why("white")));
  }
  if (const NoiseModelTerm* b = term(NoiseKind::kFlicker)) {
    out.push_back(from_model("bias_instability", b->value, b->value_lo, b->value_hi, unit));
  } else {
    out.push_back(
        from_allan_line("bias_instability", allan.bias_instability, unit, why("flicker")));
  }
  if (model) {
    std::vector<const NoiseModelTerm*> gm;
    for (const NoiseModelTerm& t : model->terms) {
      if (t.kind == NoiseKind::kGaussMarkov) gm.push_back(&t);
    }
    std::sort(gm.begin(), gm.end(), [](auto* a, auto* b) { return a->tau_s < b->tau_s; });
    for (const NoiseModelTerm* t : gm) {
      out.push_back(from_model("gauss_markov_sigma", t->value, t->value_lo, t->value_hi, unit));
      out.push_back(from_model("gauss_markov_tau", t->tau_s, t->tau_lo_s, t->tau_hi_s, "s"));
    }
  }
  if (const NoiseModelTerm* k = term(NoiseKind::kRandomWalk)) {
    out.push_back(from_model("random_walk", k->value, k->value_lo, k->value_hi, unit + "/sqrt(s)"));
  } else {
    out.push_back(from_allan_line("random_walk", allan.rate_random_walk, unit + "/sqrt(s)",
                                  why("random-walk")));
  }
  return out;
}

namespace {

/// channel_noise_models() with the identification of one channel given: from its samples or
/// from its wavelet moments.
using IdentifyChannel = std::function<NoiseModel(const ChannelNoise&, const NoiseIdOptions&)>;

std::vector<ChannelModelFigures> noise_models_by(const RunNoise& noise,
                                                 const ModelFigureOptions& options,
                                                 const IdentifyChannel& identify_channel) {
  NoiseIdOptions id = options.id;
  if (id.min_tau_s <= 0.0 && noise.sample_rate_hz > 0.0) {
    id.min_tau_s = options.min_tau_samples / noise.sample_rate_hz;
  }
  id.validate();
  // One identification per channel (about 0.4 s each on 10 min at 400 Hz), independent and
  // thread safe: spread over the cores, since `calibrate` runs them for every unit's record.
  std::vector<ChannelModelFigures> out(noise.channels.size());
  const auto identify = [&](std::size_t i) {
    const ChannelNoise& c = noise.channels[i];
    ChannelModelFigures& m = out[i];
    m.channel = c.channel;
    m.min_tau_s = id.min_tau_s;
    if (noise.duration_s < options.min_record_s) {
      m.note = fmt::format(
          "the record lasts {:.0f} s; the identified model is used from {:.0f} s (too few long "
          "scales to select its terms)",
          noise.duration_s, options.min_record_s);
    } else {
      try {
        m.model = identify_channel(c, id);
      } catch (const core::InputError& e) {
        m.note = fmt::format("no model identified: {}", e.what());
      }
    }
    m.figures = model_figures(m.model, c.terms, std::string(channel_unit(c.channel)), m.note);
  };
  const std::size_t workers =
      noise.duration_s < options.min_record_s
          ? 1
          : std::clamp<std::size_t>(std::thread::hardware_concurrency(), 1, out.size());
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  const auto work = [&] {
    for (std::size_t i = next++; i < out.size(); i = next++) {
      try {
        identify(i);
      } catch (...) {  // not an InputError: carried to the caller's thread
        const std::lock_guard lock(failure_mutex);
        if (!failure) failure = std::current_exception();
      }
    }
  };
  std::vector<std::jthread> helpers;
  for (std::size_t t = 1; t < workers; ++t) helpers.emplace_back(work);
  work();
  helpers.clear();  // joins
  if (failure) std::rethrow_exception(failure);
  return out;
}

}  // namespace

std::vector<ChannelModelFigures> channel_noise_models(std::span<const core::ImuSample> samples,
                                                      const RunNoise& noise,
                                                      const ModelFigureOptions& options) {
  return noise_models_by(noise, options, [&](const ChannelNoise& c, const NoiseIdOptions& id) {
    return identify_noise_model(channel_series(samples, c.channel), noise.sample_rate_hz, id);
  });
}

std::vector<ChannelModelFigures> channel_noise_models(store::Database& db, const RunNoise& noise,
                                                      const ModelFigureOptions& options) {
  // A streamed analysis kept each channel's wavelet moments: the model needs no second read of
  // the step. The bootstrap simulates whole records, so it keeps the path over the samples.
  const bool have_moments =
      !noise.channels.empty() && options.id.bootstrap == 0 &&
      std::all_of(noise.channels.begin(), noise.channels.end(),
                  [](const ChannelNoise& c) { return c.moments.has_value(); });
  if (have_moments) {
    return noise_models_by(noise, options, [](const ChannelNoise& c, const NoiseIdOptions& id) {
      return identify_noise_model(*c.moments, id);
    });
  }
  if (noise.duration_s < options.min_record_s) {
    // The model is not used: no need to read the record again.
    return channel_noise_models(std::span<const core::ImuSample>(), noise, options);
  }
  const std::vector<core::ImuSample> samples =
      store::read_samples(db, noise.run, noise.step, noise.device);
  return channel_noise_models(samples, noise, options);
}

}  // namespace calstand::solver

// How often diagnose finds a gyro warm-up (issue 28), by noise class, amplitude (times a static
// step mean's noise, white and wander), time constant and whether the run starts with a 30 min
// static capture; and how often it suggests anything on the same runs without a warm-up (false
// alarms). A plain program: calstand_warm_up_detection_bench [SEEDS=4] [CLASS] [clean] (CLASS:
// white, ln200, adis16488, mems or all; all by default) prints one line per cell and a JSON line
// per cell; with `clean`, only runs without a warm-up, SEEDS per class and capture; with
// `evidence [TIMES=5]`, the warm-up each diagnosis judged, one JSON line per run and sensor
// (TIMES 0: the clean runs; a fifth argument: the first seed's index); with `floor`, the white
// noise floor diagnose measures on SEEDS clean runs of CLASS beside the simulated truth's. A
// run "finds" the warm-up when diagnose says NOT explained and its first suggestion is
// exp(-elapsed/tau) on the gyros with tau within a factor 2 of the truth.
#include <fmt/format.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "../tests/unit/analysis/static_run_wander.hpp"
#include "../tests/unit/solver/warm_up_campaign.hpp"
#include "sim/imu_truth.hpp"
#include "solver/diagnose.hpp"
#include "solver/noise_rows.hpp"
#include "solver/step_noise.hpp"
#include "solver/step_summary.hpp"

namespace {

using namespace calstand;

bool found(const solver::Diagnosis& d, double tau_s) {
  if (d.explained || d.suggestions.empty()) return false;
  const std::string& top = d.suggestions.front().custom;
  const auto at = top.find(":exp(-elapsed/");
  if (top.find("=gyro") == std::string::npos || at == std::string::npos) return false;
  const double tau = std::stod(top.substr(at + 14));
  return tau > tau_s / 2.0 && tau < 2.0 * tau_s;
}

/// A run without a warm-up on the false-alarm seeds (distinct from the sweep's): the unit, its
/// true model and the campaign, with or without the capture.
struct CleanRun {
  std::uint64_t seed = 0;
  sim::ImuTruth truth;
  solver::Model model;
  solver::RunData data;
};
CleanRun clean_run(const char* noise, int k, double capture_s) {
  CleanRun r;
  r.seed = static_cast<std::uint64_t>(90000 + 131 * k);
  r.truth = solver::testing::unit_of(noise, r.seed);
  r.model = solver::Model::parse(solver::testing::true_terms(r.truth));
  r.data = solver::testing::warm_up_run(r.truth, capture_s, 900.0, 0.0, r.seed + 2);
  return r;
}

/// The k-th unit of a sweep of `noise`: on the sweep's seeds with a warm-up of `times` step
/// means' noise, or on the false-alarm seeds (distinct) for a clean run when `times` is 0.
struct SweepUnit {
  std::uint64_t seed = 0;
  sim::ImuTruth truth;
  double amplitude_dps = 0.0;
  solver::Model model;
};
SweepUnit sweep_unit(const char* noise, int k, double times) {
  SweepUnit u;
  u.seed = static_cast<std::uint64_t>(times > 0.0 ? 7000 + 97 * k : 90000 + 131 * k);
  u.truth = solver::testing::unit_of(noise, u.seed);
  u.amplitude_dps =
      times > 0.0 ? times * solver::testing::step_mean_noise_dps(u.truth, u.seed + 1) : 0.0;
  u.model = solver::Model::parse(solver::testing::true_terms(u.truth));
  return u;
}

}  // namespace

/// The false-alarm rate alone: `seeds` clean runs (no warm-up) per class and capture, seeds
/// distinct from the sweep's, and what was suggested on each that got a suggestion.
int false_alarms(int seeds, const std::string& only) {
  for (const char* noise : {"white", "ln200", "adis16488", "mems"}) {
    if (!only.empty() && only != noise) continue;
    for (double capture_s : {0.0, 1800.0}) {
      int alarms = 0;
      for (int k = 0; k < seeds; ++k) {
        const CleanRun run = clean_run(noise, k, capture_s);
        const solver::Diagnosis d = solver::diagnose(run.data, run.model);
        if (d.suggestions.empty()) continue;
        ++alarms;
        fmt::print("  false alarm: {} seed {} capture {:.0f} s: {} (delta BIC {:.1f})\n", noise,
                   run.seed, capture_s, d.suggestions.front().custom,
                   d.suggestions.front().delta_bic);
      }
      fmt::print("{:10} capture {:5.0f} s: false alarms {}/{}\n", noise, capture_s, alarms, seeds);
      fmt::print("{{\"noise\": \"{}\", \"capture_s\": {}, \"false_alarms\": {}, \"runs\": {}}}\n",
                 noise, capture_s, alarms, seeds);
      std::fflush(stdout);
    }
  }
  return 0;
}

/// The evidence itself, one JSON line per run and sensor: the warm-up each diagnosis judged
/// (time constant, 2 ln LR against the wander, BIC, held-out, kept), on warm-ups of `times`
/// step means' noise at each time constant, or on clean runs when `times` is 0, so that a bar
/// can be weighed against both rates.
int evidence(int seeds, const std::string& only, double times, int first) {
  for (const char* noise : {"white", "ln200", "adis16488", "mems"}) {
    if (!only.empty() && only != noise) continue;
    for (double capture_s : {0.0, 1800.0}) {
      for (double tau_s : {0.0, 300.0, 900.0, 1800.0}) {
        if ((tau_s > 0.0) != (times > 0.0)) continue;
        for (int k = first; k < first + seeds; ++k) {
          const SweepUnit unit = sweep_unit(noise, k, tau_s > 0.0 ? times : 0.0);
          const auto& [seed, truth, amplitude, model] = unit;
          const solver::RunData data = solver::testing::warm_up_run(
              truth, capture_s, tau_s > 0.0 ? tau_s : 900.0, amplitude, seed + 2);
          const solver::Diagnosis d = solver::diagnose(data, model);
          const bool hit = tau_s > 0.0 && found(d, tau_s);
          const std::string top = d.suggestions.empty() ? "" : d.suggestions.front().custom;
          for (const solver::WarmUpCheck& w : d.warm_ups) {
            fmt::print(
                "{{\"noise\": \"{}\", \"capture_s\": {}, \"true_tau_s\": {}, \"times\": {}, "
                "\"seed\": {}, \"custom\": \"{}\", \"tau_s\": {}, \"two_ln_lr\": {:.2f}, "
                "\"noise_penalty_change\": {:.2f}, \"delta_bic\": {:.2f}, \"held_out_better\": "
                "{}, \"kept\": {}, \"found\": {}, \"top\": \"{}\", \"verdict\": \"{}\"}}\n",
                noise, capture_s, tau_s, tau_s > 0.0 ? times : 0.0, seed, w.custom, w.tau_s,
                w.two_log_likelihood_ratio, w.noise_penalty_change, w.delta_bic, w.held_out_better,
                w.kept, hit, top, w.verdict);
          }
          std::fflush(stdout);
        }
      }
    }
  }
  return 0;
}

/// The white noise floor measured on the noise rows of `seeds` clean runs of `noise` (per
/// sample, per channel) beside the simulated truth's white noise per sample.
int floor_probe(int seeds, const std::string& noise) {
  for (double capture_s : {0.0, 1800.0}) {
    for (int k = 0; k < seeds; ++k) {
      const CleanRun run = clean_run(noise.c_str(), k, capture_s);
      const sim::ImuTruth& truth = run.truth;
      const auto rows = solver::summarize_noise_rows(run.data, run.model,
                                                     solver::summarize_steps(run.data, run.model));
      const Eigen::Matrix<double, 6, 1> sigma =
          solver::measure_noise_floor(rows).density.cwiseSqrt();
      // The truth's white noise is a density [unit/sqrt(Hz)]: per sample, times sqrt(rate).
      const double root_rate = std::sqrt(truth.sample_rate_hz);
      fmt::print(
          "{:10} capture {:4.0f} s seed {}: white per sample gyro {:.3g} {:.3g} {:.3g} deg/s "
          "(truth {:.3g}), accel {:.3g} {:.3g} {:.3g} m/s^2 (truth {:.3g})\n",
          noise, capture_s, run.seed, sigma[0], sigma[1], sigma[2],
          truth.gyro_noise.white[0] * root_rate, sigma[3], sigma[4], sigma[5],
          truth.accel_noise.white[0] * root_rate);
    }
  }
  return 0;
}

/// The simulated truth's own wander per channel (Gauss-Markov, flicker, rate random walk; the
/// solver spreads a flicker over the campaign's band): the noise an oracle knows, for `known TIMES
/// 0` (HOURS 0).
solver::KnownWander truth_wander(const sim::ImuTruth& truth) {
  solver::KnownWander known;
  known.source = "the simulated truth";
  for (int c = 0; c < solver::kChannels; ++c) {
    const sim::TriadNoise& n = c < 3 ? truth.gyro_noise : truth.accel_noise;
    const int axis = c % 3;
    std::vector<solver::WanderModel> parts;
    if (n.gauss_markov_sigma[axis] > 0.0) {
      solver::WanderModel gm;
      gm.kind = solver::WanderKind::kGaussMarkov;
      gm.sigma = n.gauss_markov_sigma[axis];
      gm.tau_s = n.gauss_markov_tau_s;
      parts.push_back(gm);
    }
    if (n.bias_instability[axis] > 0.0) {
      solver::WanderModel f;
      f.kind = solver::WanderKind::kFlicker;
      f.flicker_b = n.bias_instability[axis];
      parts.push_back(f);
    }
    if (n.random_walk[axis] > 0.0) {
      solver::WanderModel rw;
      rw.kind = solver::WanderKind::kRandomWalk;
      rw.random_walk_k = n.random_walk[axis];
      parts.push_back(rw);
    }
    if (parts.size() == 1) known.wander[static_cast<std::size_t>(c)] = parts.front();
    if (parts.size() > 1) {
      known.wander[static_cast<std::size_t>(c)].kind = solver::WanderKind::kSum;
      known.wander[static_cast<std::size_t>(c)].parts = parts;
    }
  }
  return known;
}

/// Found and false alarms with the wander known from a static run of the same unit (`diagnose
/// --noise-run`): per class, capture and time constant, warm-ups of `times` on the sweep's
/// seeds and the same runs without it; one line per run with the decision's figures.
int known_wander(int seeds, const std::string& only, double times, double hours) {
  for (const char* noise : {"white", "ln200", "adis16488", "mems"}) {
    if (!only.empty() && only != noise) continue;
    for (double capture_s : {0.0, 1800.0}) {
      for (double tau_s : {300.0, 900.0, 1800.0}) {
        // times 0: clean runs alone, on the false-alarm seeds (one set per capture).
        if (times == 0.0 && tau_s != 900.0) continue;
        int hits = 0, alarms = 0;
        for (int k = 0; k < seeds; ++k) {
          const SweepUnit unit = sweep_unit(noise, k, times);
          const auto& [seed, truth, amplitude, model] = unit;
          for (double a :
               times > 0.0 ? std::vector<double>{amplitude, 0.0} : std::vector<double>{0.0}) {
            const solver::RunData data =
                solver::testing::warm_up_run(truth, capture_s, tau_s, a, seed + 2);
            solver::DiagnoseOptions options;
            options.noise.known_wander =
                hours > 0.0 ? calstand::testing::static_run_wander(truth, hours, seed + 3, data)
                            : truth_wander(truth);
            const solver::Diagnosis d = solver::diagnose(data, model, {}, options);
            const bool hit = a > 0.0 && found(d, tau_s);
            const bool alarm = a == 0.0 && !d.suggestions.empty();
            hits += hit ? 1 : 0;
            alarms += alarm ? 1 : 0;
            for (const solver::WarmUpCheck& w : d.warm_ups) {
              fmt::print(
                  "{{\"noise\": \"{}\", \"capture_s\": {}, \"true_tau_s\": {}, \"times\": "
                  "{}, \"seed\": {}, \"custom\": \"{}\", \"two_ln_lr\": {:.2f}, "
                  "\"delta_bic\": {:.2f}, \"kept\": {}, \"found\": {}, \"alarm\": {}, "
                  "\"verdict\": \"{}\"}}\n",
                  noise, capture_s, tau_s, a > 0.0 ? times : 0.0, seed, w.custom,
                  w.two_log_likelihood_ratio, w.delta_bic, w.kept, hit, alarm, w.verdict);
            }
          }
          std::fflush(stdout);
        }
        fmt::print(
            "{:10} capture {:5.0f} s tau {:5.0f} s {:4.0f}x, wander from a {} h static "
            "run: found {}/{}, false alarms without it {}/{}\n",
            noise, capture_s, tau_s, times, hours, hits, seeds, alarms, seeds);
        std::fflush(stdout);
      }
    }
  }
  return 0;
}

int main(int argc, char** argv) {
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 4;
  const std::string only = argc > 2 && std::string(argv[2]) != "all" ? argv[2] : "";
  if (argc > 3 && std::string(argv[3]) == "floor")
    return floor_probe(seeds, only.empty() ? "adis16488" : only);
  if (argc > 3 && std::string(argv[3]) == "clean") return false_alarms(seeds, only);
  if (argc > 3 && std::string(argv[3]) == "known") {
    return known_wander(seeds, only, argc > 4 ? std::atof(argv[4]) : 5.0,
                        argc > 5 ? std::atof(argv[5]) : 3.0);
  }
  if (argc > 3 && std::string(argv[3]) == "evidence") {
    return evidence(seeds, only, argc > 4 ? std::atof(argv[4]) : 5.0,
                    argc > 5 ? std::atoi(argv[5]) : 0);
  }
  for (const char* noise : {"white", "ln200", "adis16488", "mems"}) {
    if (!only.empty() && only != noise) continue;
    for (double capture_s : {0.0, 1800.0}) {
      for (double tau_s : {300.0, 900.0, 1800.0}) {
        for (double times : {5.0, 10.0, 20.0}) {
          int hits = 0, false_alarms = 0;
          for (int k = 0; k < seeds; ++k) {
            const auto seed = static_cast<std::uint64_t>(7000 + 97 * k);
            const sim::ImuTruth truth = solver::testing::unit_of(noise, seed);
            const double amplitude = times * solver::testing::step_mean_noise_dps(truth, seed + 1);
            const solver::Model model = solver::Model::parse(solver::testing::true_terms(truth));
            const solver::RunData data =
                solver::testing::warm_up_run(truth, capture_s, tau_s, amplitude, seed + 2);
            hits += found(solver::diagnose(data, model), tau_s) ? 1 : 0;
            if (times == 5.0) {
              const solver::RunData clean =
                  solver::testing::warm_up_run(truth, capture_s, tau_s, 0.0, seed + 2);
              false_alarms += solver::diagnose(clean, model).suggestions.empty() ? 0 : 1;
            }
          }
          fmt::print("{:10} capture {:5.0f} s tau {:5.0f} s {:4.0f}x: found {}/{}{}\n", noise,
                     capture_s, tau_s, times, hits, seeds,
                     times == 5.0
                         ? fmt::format(", false alarms without it {}/{}", false_alarms, seeds)
                         : std::string());
          fmt::print(
              "{{\"noise\": \"{}\", \"capture_s\": {}, \"tau_s\": {}, \"times\": {}, \"found\": "
              "{}, "
              "\"runs\": {}}}\n",
              noise, capture_s, tau_s, times, hits, seeds);
          std::fflush(stdout);
        }
      }
    }
  }
  return 0;
}

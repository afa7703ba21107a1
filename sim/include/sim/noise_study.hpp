#pragma once

#include <cstdint>
#include <vector>

namespace calstand::sim {

/// Exercise 2 of the seed notes ("simulation of common random processes") as a reproducible
/// study. Rates are in deg/h, angles in deg.
struct NoiseStudyOptions {
  int runs = 100;  ///< Monte-Carlo runs (random-walk sigmas need >= 100)
  std::uint64_t seed = 1;
  double white_sigma_dph = 0.03;  ///< per-sample sigma of the raw white noise [deg/h]
  double sample_rate_hz = 1000.0;
  double duration_s = 3600.0;
  int filter_order = 2;  ///< Butterworth order of the band-limiting filters
  std::vector<double> cutoffs_hz{100.0, 10.0, 1.0};
  std::vector<double> walk_times_s{10.0, 60.0, 360.0, 3600.0};
  std::vector<double> gm_taus_s{4.0, 40.0, 400.0, 4000.0};
};

struct WhiteNoiseRow {
  double cutoff_hz;  ///< low-pass cutoff; the raw noise row uses sample_rate/2
  double rms;        ///< simulated RMS [deg/h]
  /// sigma * sqrt(sum of h_k^2), h the impulse response of the digital filter actually used
  /// (ButterworthLowPass::white_noise_power_gain()): exact for the stationary output [deg/h].
  double theory;
  /// The textbook figure sigma * sqrt(ENBW / (fs/2)) with the ENBW of the analog prototype
  /// [deg/h]; the bilinear transform's zeros at fs/2 make the digital filter pass a little
  /// less (1.8 % in RMS at 100 Hz of 1 kHz, 0.03 % at 10 Hz).
  double theory_analog;
};

struct RandomWalkRow {
  double t_s;     ///< integration time [s]
  double sigma;   ///< std of the integrated angle across runs [deg]
  double theory;  ///< sigma_rate * sqrt(dt * t), sigma_rate in deg/s [deg]
};

/// The raw white samples n_k drive x_k = phi x_{k-1} + c n_k, i.e. they are the increments of
/// dx/dt = -x/tau + w(t), whose white noise w has PSD q = sigma_w^2 / dt (the seed notes'
/// q_k ~= q dt); c ~= 1 is set so the stationary variance is exactly q tau / 2.
struct GaussMarkovRow {
  double tau_s;   ///< correlation time [s]
  double q;       ///< PSD of the driving white noise w [(deg/h)^2/s]
  double sigma;   ///< RMS over all samples of all runs [deg/h]
  double theory;  ///< stationary sigma sqrt(q tau / 2) [deg/h]
  /// Mean over runs of each run's own de-meaned sigma [deg/h]: close to sigma when tau is much
  /// shorter than a run (white-like), far below it when tau is much longer (random-walk-like).
  double within_run_sigma;
};

struct NoiseStudyResult {
  std::vector<WhiteNoiseRow> white;
  std::vector<RandomWalkRow> random_walk;
  std::vector<GaussMarkovRow> gauss_markov;
};

/// Runs the study: each run draws one raw white sequence (seeded by derive_seed(seed,
/// "noise_study.white", run)) and feeds it to every part, as the exercise does. Deterministic in
/// the options. Single threaded; about 3.6e8 samples with the defaults.
/// Throws std::invalid_argument naming the option when one is out of range.
NoiseStudyResult run_noise_study(const NoiseStudyOptions& options);

}  // namespace calstand::sim

#pragma once

#include <cstdint>
#include <random>
#include <string_view>
#include <vector>

namespace calstand::sim {

/// The simulator's random engine. Every noise source owns one, seeded from the station seed by
/// derive_seed(), so adding a source never shifts the numbers another source draws.
using Rng = std::mt19937_64;

/// Independent seed for the stream `name` number `index` under the station seed (hash-mixed;
/// the same inputs always give the same seed).
std::uint64_t derive_seed(std::uint64_t seed, std::string_view name, std::uint64_t index = 0);

/// Standard normal draws from an owned, seeded engine.
class NormalSource {
 public:
  explicit NormalSource(std::uint64_t seed) : rng_(seed) {}
  double next() { return normal_(rng_); }

 private:
  Rng rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

/// Sampled white noise of density N [unit/sqrt(Hz)], i.e. the
/// angle (or velocity) random walk coefficient in SI-like seconds: per-sample sigma is
/// N * sqrt(sample_rate_hz). Its Allan deviation is N / sqrt(tau).
class WhiteNoise {
 public:
  WhiteNoise(double density_per_sqrt_hz, double sample_rate_hz, std::uint64_t seed);
  double next();
  double sigma() const { return sigma_; }  ///< per-sample standard deviation [unit]

 private:
  double sigma_;
  NormalSource normal_;
};

/// Random walk of the output (rate random walk for a gyro, acceleration random walk for an
/// accelerometer): x_{k+1} = x_k + K sqrt(dt) n_k with K in [unit/sqrt(s)]. Allan deviation
/// K sqrt(tau/3). Starts at zero.
class RandomWalk {
 public:
  RandomWalk(double k_per_sqrt_s, double dt_s, std::uint64_t seed);
  double next();  ///< advances one step and returns the new value
  double value() const { return value_; }

 private:
  double step_sigma_;
  double value_ = 0.0;
  NormalSource normal_;
};

/// First-order Gauss-Markov process with stationary sigma and correlation time tau, discretised
/// exactly: x_{k+1} = phi x_k + w_k, phi = exp(-dt/tau), var(w) = sigma^2 (1 - phi^2).
/// Starts from a draw of the stationary distribution (or from zero when asked).
class GaussMarkov {
 public:
  GaussMarkov(double sigma, double tau_s, double dt_s, std::uint64_t seed,
              bool start_stationary = true);
  double next();
  double value() const { return value_; }
  double phi() const { return phi_; }
  double drive_sigma() const { return drive_sigma_; }

 private:
  double phi_;
  double drive_sigma_;
  double value_ = 0.0;
  NormalSource normal_;
};

/// Bias instability (flicker, 1/f) noise of coefficient B [unit], as IEEE Std 952 defines it:
/// the Allan deviation floor is B * sqrt(2 ln2 / pi) ~= 0.664 B. Approximated by a sum of
/// first-order Gauss-Markov processes with correlation times log-spaced over
/// [tau_min_s, tau_max_s]; the Allan deviation is flat to within about 10 % between roughly
/// 2 tau_min and tau_max.
class BiasInstability {
 public:
  BiasInstability(double coefficient, double dt_s, std::uint64_t seed, double tau_min_s = 1.0,
                  double tau_max_s = 3000.0);
  double next();
  /// The Allan deviation level the process is scaled to: 0.664 * coefficient.
  double allan_floor() const { return allan_floor_; }

 private:
  double allan_floor_;
  std::vector<GaussMarkov> components_;
};

/// Quantizer of a rate output with LSB `lsb` that carries the rounding residue to the next
/// sample, as an integrating (delta-angle) output does: the integral of the output is exact to
/// one LSB*dt, and the Allan deviation has the quantization-noise slope (tau^-1). lsb <= 0
/// passes values through.
class Quantizer {
 public:
  explicit Quantizer(double lsb) : lsb_(lsb) {}
  double apply(double x);

 private:
  double lsb_;
  double residue_ = 0.0;
};

/// Butterworth low-pass of even order (2, 4, 6, 8) as a cascade of bilinear-transform biquads
/// with the cutoff pre-warped. cutoff_hz must lie in (0, sample_rate_hz / 2).
class ButterworthLowPass {
 public:
  ButterworthLowPass(int order, double cutoff_hz, double sample_rate_hz);
  double filter(double x);
  /// Puts every section at its steady state for a constant input x (no start-up transient).
  void reset(double x);
  int order() const { return order_; }
  /// Noise-equivalent bandwidth of the analog prototype [Hz]:
  /// cutoff * (pi / 2n) / sin(pi / 2n).
  double noise_equivalent_bandwidth_hz() const;
  /// Sum of squares of the digital impulse response (the exact variance gain for white input).
  double white_noise_power_gain() const;

 private:
  struct Biquad {
    double b0, b1, b2, a1, a2;  // a0 normalised to 1
    double z1 = 0.0, z2 = 0.0;  // transposed direct form II state
  };
  int order_;
  double cutoff_hz_;
  std::vector<Biquad> sections_;
};

}  // namespace calstand::sim

#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string_view>
#include <vector>

#include "sim/random_engine.hpp"

namespace calstand::sim {

/// The simulator's random engine. Every noise source owns one, seeded from the station seed by
/// derive_seed(), so adding a source never shifts the numbers another source draws.
using Rng = Xoshiro256pp;

/// Independent seed for the stream `name` number `index` under the station seed (splitmix64
/// mixing of the seed, an FNV-1a hash of the name and the index; the same inputs always give the
/// same seed, on every platform).
std::uint64_t derive_seed(std::uint64_t seed, std::string_view name, std::uint64_t index = 0);

namespace detail {
/// Layer edges x[0..256] (x[0] is the base strip's pseudo-width, x[1] = r, x[256] = 0) and
/// f[i] = exp(-x[i]^2 / 2) of the 256-layer normal ziggurat (Marsaglia and Tsang 2000).
struct ZigguratTable {
  double x[257];
  double f[257];
};
/// The table, built once on first use (thread safe).
const ZigguratTable& ziggurat_table();
/// The rare part of a draw (about 1.2 % of them): the tail of layer 0 or the wedge of another
/// layer. Returns true and sets `x` to the magnitude when the point is accepted, false when the
/// draw must start again.
bool ziggurat_edge(Rng& rng, const ZigguratTable& table, unsigned layer, double& x);
}  // namespace detail

/// Standard normal draws from an owned, seeded engine, by the ziggurat method: one 64-bit draw
/// per sample on the fast path (about ten times faster than std::normal_distribution), and the
/// sequence is the same on every platform since the algorithm is ours, not the library's.
/// Not thread safe; give each thread its own source.
class NormalSource {
 public:
  explicit NormalSource(std::uint64_t seed) : rng_(seed), table_(&detail::ziggurat_table()) {}
  double next() {
    for (;;) {
      // Disjoint bits for the layer (0-7), the sign (8) and the abscissa (11-63): sharing bits
      // between layer and abscissa is the known defect of the original ziggurat code.
      const std::uint64_t bits = rng_();
      const auto layer = static_cast<unsigned>(bits & 0xffU);
      const bool negative = (bits & 0x100U) != 0;
      double x = static_cast<double>(bits >> 11U) * 0x1.0p-53 * table_->x[layer];
      if (x < table_->x[layer + 1] || detail::ziggurat_edge(rng_, *table_, layer, x)) {
        return negative ? -x : x;
      }
    }
  }

 private:
  Rng rng_;
  const detail::ZigguratTable* table_;
};

/// Sampled white noise of density N [unit/sqrt(Hz)], i.e. the
/// angle (or velocity) random walk coefficient in SI-like seconds: per-sample sigma is
/// N * sqrt(sample_rate_hz). Its Allan deviation is N / sqrt(tau).
/// Throws std::invalid_argument for a negative or non-finite density or a non-positive rate.
class WhiteNoise {
 public:
  WhiteNoise(double density_per_sqrt_hz, double sample_rate_hz, std::uint64_t seed);
  double next() { return sigma_ * normal_.next(); }
  double sigma() const { return sigma_; }  ///< per-sample standard deviation [unit]

 private:
  double sigma_;
  NormalSource normal_;
};

/// Random walk of the output (rate random walk for a gyro, acceleration random walk for an
/// accelerometer): x_{k+1} = x_k + K sqrt(dt) n_k with K in [unit/sqrt(s)]. Allan deviation
/// K sqrt(tau/3). Starts at zero.
/// Throws std::invalid_argument for a negative or non-finite K or a non-positive dt.
class RandomWalk {
 public:
  RandomWalk(double k_per_sqrt_s, double dt_s, std::uint64_t seed);
  /// Advances one step and returns the new value [unit].
  double next() {
    value_ += step_sigma_ * normal_.next();
    return value_;
  }
  double value() const { return value_; }

 private:
  double step_sigma_;
  double value_ = 0.0;
  NormalSource normal_;
};

/// First-order Gauss-Markov process with stationary sigma and correlation time tau, discretised
/// exactly: x_{k+1} = phi x_k + w_k, phi = exp(-dt/tau), var(w) = sigma^2 (1 - phi^2).
/// Starts from a draw of the stationary distribution (or from zero when asked, in which case
/// the variance grows as sigma^2 (1 - exp(-2 t / tau))).
/// Throws std::invalid_argument for a negative or non-finite sigma or a non-positive tau or dt.
class GaussMarkov {
 public:
  GaussMarkov(double sigma, double tau_s, double dt_s, std::uint64_t seed,
              bool start_stationary = true);
  /// Advances one step and returns the new value [unit].
  double next() {
    value_ = phi_ * value_ + drive_sigma_ * normal_.next();
    return value_;
  }
  double value() const { return value_; }
  double phi() const { return phi_; }                  ///< one-step autocorrelation
  double drive_sigma() const { return drive_sigma_; }  ///< sigma of w_k [unit]

 private:
  double phi_;
  double drive_sigma_;
  double value_ = 0.0;
  NormalSource normal_;
};

/// Allan variance [unit^2] at averaging time averaging_time_s of a continuous first-order
/// Gauss-Markov process of stationary sigma and correlation time tau_c_s:
/// (2 sigma^2 tau_c^2 / T^2) (T/tau_c - 3/2 + 2 e^{-T/tau_c} - e^{-2T/tau_c} / 2).
/// It rises as 2 sigma^2 T / (3 tau_c) for T << tau_c, peaks near T = 1.89 tau_c and falls as
/// 2 sigma^2 tau_c / T. A sampled process follows it while dt << tau_c.
double gauss_markov_allan_variance(double sigma, double tau_c_s, double averaging_time_s);

/// Allan deviation floor of flicker (bias instability) noise per unit of its IEEE Std 952
/// coefficient B: sqrt(2 ln2 / pi) ~= 0.664. Datasheets quote the floor; truth files hold B.
inline const double kFlickerAllanFloorPerCoefficient =
    std::sqrt(2.0 * std::numbers::ln2 / std::numbers::pi);

/// Bias instability (flicker, 1/f) noise of coefficient B [unit], as IEEE Std 952 defines it:
/// the Allan deviation floor is B * sqrt(2 ln2 / pi) ~= 0.664 B. Approximated by a sum of
/// first-order Gauss-Markov processes with correlation times log-spaced over
/// [tau_min_s, tau_max_s]; the Allan deviation is flat to within about 10 % between roughly
/// 2 tau_min and tau_max (the model's own ripple is within +-5 %, see model_allan_deviation()).
/// Needs dt << tau_min to hold. Throws std::invalid_argument for a negative or non-finite B, a
/// non-positive dt, tau_min_s <= dt_s or tau_max_s < 2 tau_min_s.
class BiasInstability {
 public:
  BiasInstability(double coefficient, double dt_s, std::uint64_t seed, double tau_min_s = 1.0,
                  double tau_max_s = 3000.0);
  /// Advances one step and returns the new value [unit]. Slow components are updated every
  /// few steps (see the constructor), so a step costs well under one normal draw on average.
  double next() {
    double sum = 0.0;
    for (Component& c : components_) {
      if (--c.countdown == 0) {
        c.value = c.phi * c.value + c.drive_sigma * normal_.next();
        c.countdown = c.stride;
      }
      sum += c.value;
    }
    return sum;
  }
  /// The Allan deviation level the process is scaled to: 0.664 * coefficient [unit].
  double allan_floor() const { return allan_floor_; }
  /// Analytic Allan deviation of the continuous-time model at averaging time tau_s [unit]: the
  /// root of the sum of the components' Gauss-Markov Allan variances.
  double model_allan_deviation(double tau_s) const;
  std::size_t component_count() const { return components_.size(); }

 private:
  struct Component {
    double phi;          // exp(-stride dt / tau)
    double drive_sigma;  // exact drive over one hold of `stride` steps
    double value;
    std::uint32_t stride;     // steps between updates
    std::uint32_t countdown;  // steps until the next update
  };
  double allan_floor_;
  std::vector<Component> components_;
  std::vector<double> taus_s_;     // correlation time of each component [s]
  std::vector<double> variances_;  // stationary variance of each component [unit^2]
  NormalSource normal_;            // one engine for all components keeps next() cache-friendly
};

/// Quantizer of a rate output with LSB `lsb` that carries the rounding residue to the next
/// sample, as an integrating (delta-angle) output does: the integral of the output is exact to
/// one LSB*dt, and the Allan deviation has the quantization-noise slope (tau^-1). lsb <= 0
/// passes values through. Throws std::invalid_argument for a NaN or infinite lsb.
class Quantizer {
 public:
  explicit Quantizer(double lsb);
  /// Returns a multiple of lsb; the running sum of outputs never differs from the running sum
  /// of inputs by more than lsb / 2.
  double apply(double x);

 private:
  double lsb_;
  double residue_ = 0.0;
};

/// Butterworth low-pass of even order (2, 4, 6, 8) as a cascade of bilinear-transform biquads
/// with the cutoff pre-warped, so the -3 dB point of the digital filter is exactly cutoff_hz.
/// cutoff_hz must lie in (0, sample_rate_hz / 2); otherwise, or for another order, throws
/// std::invalid_argument. Starts at rest (zero state).
class ButterworthLowPass {
 public:
  ButterworthLowPass(int order, double cutoff_hz, double sample_rate_hz);
  /// Filters one sample.
  double filter(double x) {
    for (Biquad& s : sections_) {
      // Transposed direct form II: two state variables per section and good rounding behaviour.
      const double y = s.b0 * x + s.z1;
      s.z1 = s.b1 * x - s.a1 * y + s.z2;
      s.z2 = s.b2 * x - s.a2 * y;
      x = y;
    }
    return x;
  }
  /// Puts every section at its steady state for a constant input x (no start-up transient).
  void reset(double x);
  int order() const { return order_; }
  double cutoff_hz() const { return cutoff_hz_; }
  /// Noise-equivalent bandwidth of the analog prototype [Hz]:
  /// cutoff * (pi / 2n) / sin(pi / 2n).
  double noise_equivalent_bandwidth_hz() const;
  /// Sum of squares of the digital impulse response (the exact variance gain for white input).
  /// Computed on each call by running the impulse response until it has decayed.
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

#include "sim/noise.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace calstand::sim {

namespace {

// splitmix64's finaliser: a bijection on 64 bits with full avalanche, so nearby inputs (seed 1
// and seed 2, index 0 and index 1) give unrelated outputs.
constexpr std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30U)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27U)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31U);
}

constexpr std::uint64_t kGolden = 0x9e3779b97f4a7c15ULL;

std::uint64_t fnv1a64(std::string_view text) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (const char c : text) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

[[noreturn]] void throw_bad(std::string_view who, std::string_view argument, double value,
                            std::string_view rule) {
  throw std::invalid_argument(
      fmt::format("{}: {} must be {} (got {})", who, argument, rule, value));
}

void require_non_negative(std::string_view who, std::string_view argument, double value) {
  if (!std::isfinite(value) || value < 0.0) throw_bad(who, argument, value, "finite and >= 0");
}

void require_positive(std::string_view who, std::string_view argument, double value) {
  if (!std::isfinite(value) || value <= 0.0) throw_bad(who, argument, value, "finite and > 0");
}

// sqrt(1 - exp(-2 dt / tau)) without the cancellation 1 - phi^2 suffers when dt << tau.
double stationary_drive_factor(double dt_s, double tau_s) {
  return std::sqrt(-std::expm1(-2.0 * dt_s / tau_s));
}

}  // namespace

namespace detail {

namespace {

// 256 layers of equal area v under f(x) = exp(-x^2/2); r is the start of the tail
// (Marsaglia and Tsang, "The Ziggurat Method for Generating Random Variables", JSS 2000).
constexpr double kZigR = 3.6541528853610088;
constexpr double kZigV = 0.00492867323399;

ZigguratTable build_ziggurat() {
  ZigguratTable t{};
  const double fr = std::exp(-0.5 * kZigR * kZigR);
  t.x[0] = kZigV / fr;  // base strip plus tail, as a rectangle of height f(r)
  t.f[0] = 0.0;         // unused: layer 0 has no wedge, only the tail
  t.x[1] = kZigR;
  t.f[1] = fr;
  for (int i = 1; i < 255; ++i) {
    // Layer i: [0, x_i] x [f(x_i), f(x_{i+1})] of area v.
    t.f[i + 1] = t.f[i] + kZigV / t.x[i];
    t.x[i + 1] = std::sqrt(-2.0 * std::log(t.f[i + 1]));
  }
  t.x[256] = 0.0;  // the top layer closes at the peak
  t.f[256] = 1.0;
  return t;
}

double uniform_open0(Rng& rng) {  // (0, 1], safe for log()
  return (static_cast<double>(rng() >> 11U) + 1.0) * 0x1.0p-53;
}

}  // namespace

const ZigguratTable& ziggurat_table() {
  static const ZigguratTable table = build_ziggurat();
  return table;
}

bool ziggurat_edge(Rng& rng, const ZigguratTable& table, unsigned layer, double& x) {
  if (layer == 0) {
    // Tail beyond r (Marsaglia 1964): exact, and reached once in ~4000 draws.
    double a = 0.0, b = 0.0;
    do {
      a = -std::log(uniform_open0(rng)) / kZigR;
      b = -std::log(uniform_open0(rng));
    } while (b + b < a * a);
    x = kZigR + a;
    return true;
  }
  // Wedge between the curve and the layer's rectangle: accept below the curve.
  const double y = table.f[layer] + uniform_open0(rng) * (table.f[layer + 1] - table.f[layer]);
  return y < std::exp(-0.5 * x * x);
}

}  // namespace detail

std::uint64_t derive_seed(std::uint64_t seed, std::string_view name, std::uint64_t index) {
  // Absorb the three inputs one after the other, each through the full mix, so that swapping
  // them (seed 3 index 5 versus seed 5 index 3) does not collide.
  std::uint64_t state = mix64(seed + kGolden);
  state = mix64(state ^ fnv1a64(name)) + kGolden;
  state = mix64(state ^ mix64(index + 2 * kGolden));
  return state;
}

WhiteNoise::WhiteNoise(double density_per_sqrt_hz, double sample_rate_hz, std::uint64_t seed)
    : sigma_(0.0), normal_(seed) {
  require_non_negative("WhiteNoise", "density_per_sqrt_hz", density_per_sqrt_hz);
  require_positive("WhiteNoise", "sample_rate_hz", sample_rate_hz);
  // A density N [unit/sqrt(Hz)] sampled at fs, each sample the average over dt = 1/fs, has
  // variance N^2 / dt.
  sigma_ = density_per_sqrt_hz * std::sqrt(sample_rate_hz);
}

RandomWalk::RandomWalk(double k_per_sqrt_s, double dt_s, std::uint64_t seed)
    : step_sigma_(0.0), normal_(seed) {
  require_non_negative("RandomWalk", "k_per_sqrt_s", k_per_sqrt_s);
  require_positive("RandomWalk", "dt_s", dt_s);
  step_sigma_ = k_per_sqrt_s * std::sqrt(dt_s);
}

GaussMarkov::GaussMarkov(double sigma, double tau_s, double dt_s, std::uint64_t seed,
                         bool start_stationary)
    : phi_(0.0), drive_sigma_(0.0), normal_(seed) {
  require_non_negative("GaussMarkov", "sigma", sigma);
  require_positive("GaussMarkov", "tau_s", tau_s);
  require_positive("GaussMarkov", "dt_s", dt_s);
  phi_ = std::exp(-dt_s / tau_s);
  drive_sigma_ = sigma * stationary_drive_factor(dt_s, tau_s);
  if (start_stationary) value_ = sigma * normal_.next();
}

double gauss_markov_allan_variance(double sigma, double tau_c_s, double averaging_time_s) {
  require_non_negative("gauss_markov_allan_variance", "sigma", sigma);
  require_positive("gauss_markov_allan_variance", "tau_c_s", tau_c_s);
  require_positive("gauss_markov_allan_variance", "averaging_time_s", averaging_time_s);
  const double x = averaging_time_s / tau_c_s;
  const double var = sigma * sigma;
  if (x < 1e-2) {
    // The bracket cancels to sum_{k>=3} (-1)^k (2 - 2^(k-1)) x^k / k!, so the closed form loses
    // digits as x^3 shrinks (1e-9 relative at x = 0.01); the series to k = 7 is good to 1e-10.
    return 2.0 * var * x *
           (1.0 / 3.0 +
            x * (-1.0 / 4.0 + x * (7.0 / 60.0 + x * (-1.0 / 24.0 + x * 31.0 / 2520.0))));
  }
  return 2.0 * var / (x * x) * (x - 1.5 + 2.0 * std::exp(-x) - 0.5 * std::exp(-2.0 * x));
}

BiasInstability::BiasInstability(double coefficient, double dt_s, std::uint64_t seed,
                                 double tau_min_s, double tau_max_s)
    : allan_floor_(0.0), normal_(seed) {
  require_non_negative("BiasInstability", "coefficient", coefficient);
  require_positive("BiasInstability", "dt_s", dt_s);
  require_positive("BiasInstability", "tau_min_s", tau_min_s);
  if (!(tau_min_s > dt_s)) throw_bad("BiasInstability", "tau_min_s", tau_min_s, "> dt_s");
  if (!std::isfinite(tau_max_s) || !(tau_max_s >= 2.0 * tau_min_s)) {
    throw_bad("BiasInstability", "tau_max_s", tau_max_s, "finite and >= 2 * tau_min_s");
  }
  allan_floor_ = coefficient * kFlickerAllanFloorPerCoefficient;

  // Two components per decade: the Allan variance of one Gauss-Markov process is a bump about
  // a decade and a half wide in log T, so at this spacing the interior ripple of the sum is
  // below 0.01 % (2 % at one per decade); more components would only cost normal draws.
  const double decades = std::log10(tau_max_s / tau_min_s);
  const auto count = static_cast<std::size_t>(std::max(2.0, std::ceil(2.0 * decades) + 1.0));
  const double ratio = std::pow(tau_max_s / tau_min_s, 1.0 / static_cast<double>(count - 1));
  taus_s_.resize(count);
  std::vector<double> weights(count, 1.0);
  for (std::size_t i = 0; i < count; ++i) {
    taus_s_[i] = tau_min_s * std::pow(ratio, static_cast<double>(i));
  }
  // Equal variances make the interior flat (1/f = equal power per log-frequency interval). The
  // end components also stand in for the infinite tail of components the band leaves out:
  // far from the band both the Allan variance of the missing ones (2 tau/T below, 2 T/(3 tau)
  // above) and their sum scale as a geometric series, 1 + 1/ratio + ... = ratio/(ratio-1).
  weights.front() = weights.back() = ratio / (ratio - 1.0);

  // Scale so that the model's Allan deviation over [2 tau_min, tau_max] is centred, in the
  // minimax sense on a log scale, on the floor: max/floor = floor/min.
  double lo = INFINITY, hi = 0.0;
  const double band_lo = 2.0 * tau_min_s;
  const int grid = std::max(8, static_cast<int>(std::ceil(32.0 * std::log10(tau_max_s / band_lo))));
  for (int j = 0; j <= grid; ++j) {
    const double t = band_lo * std::pow(tau_max_s / band_lo, static_cast<double>(j) / grid);
    double avar = 0.0;
    for (std::size_t i = 0; i < count; ++i) {
      avar += gauss_markov_allan_variance(std::sqrt(weights[i]), taus_s_[i], t);
    }
    lo = std::min(lo, avar);
    hi = std::max(hi, avar);
  }
  const double unit_adev = std::pow(lo * hi, 0.25);  // geometric centre of sqrt(lo), sqrt(hi)
  const double scale = allan_floor_ / unit_adev;

  variances_.resize(count);
  components_.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    variances_[i] = weights[i] * scale * scale;
    const double sigma = std::sqrt(variances_[i]);
    // A component changes little within a small fraction of its correlation time, so it is
    // advanced (exactly, over the whole hold) only every `stride` steps and held in between.
    // Holding for at most tau/kHoldsPerTau moves the Allan variance only at averaging times
    // far below tau, where this component's share is negligible next to the white noise; and
    // it cuts the normal draws per sample from one per component to a small fraction of one.
    constexpr double kHoldsPerTau = 200.0;
    const auto stride = static_cast<std::uint32_t>(
        std::clamp(std::floor(taus_s_[i] / (kHoldsPerTau * dt_s)), 1.0, 1e9));
    const double hold_s = stride * dt_s;
    // Start stationary: a flicker source has been running long before the test starts.
    components_.push_back({std::exp(-hold_s / taus_s_[i]),
                           sigma * stationary_drive_factor(hold_s, taus_s_[i]),
                           sigma * normal_.next(), stride, 1});
  }
}

double BiasInstability::model_allan_deviation(double tau_s) const {
  double avar = 0.0;
  for (std::size_t i = 0; i < taus_s_.size(); ++i) {
    avar += gauss_markov_allan_variance(std::sqrt(variances_[i]), taus_s_[i], tau_s);
  }
  return std::sqrt(avar);
}

Quantizer::Quantizer(double lsb) : lsb_(lsb) {
  if (std::isnan(lsb) || std::isinf(lsb)) throw_bad("Quantizer", "lsb", lsb, "finite");
}

double Quantizer::apply(double x) {
  if (lsb_ <= 0.0) return x;
  const double wanted = x + residue_;
  const double out = lsb_ * std::nearbyint(wanted / lsb_);
  residue_ = wanted - out;
  return out;
}

ButterworthLowPass::ButterworthLowPass(int order, double cutoff_hz, double sample_rate_hz)
    : order_(order), cutoff_hz_(cutoff_hz) {
  if (order < 2 || order > 8 || order % 2 != 0) {
    throw std::invalid_argument(
        fmt::format("ButterworthLowPass: order must be 2, 4, 6 or 8 (got {})", order));
  }
  require_positive("ButterworthLowPass", "sample_rate_hz", sample_rate_hz);
  if (!std::isfinite(cutoff_hz) || cutoff_hz <= 0.0 || cutoff_hz >= 0.5 * sample_rate_hz) {
    throw_bad("ButterworthLowPass", "cutoff_hz", cutoff_hz, "in (0, sample_rate_hz / 2)");
  }
  // Pre-warp: the bilinear transform maps analog w to digital 2 atan(w / 2fs); choosing the
  // analog cutoff as tan(pi fc / fs) puts the digital -3 dB point exactly at fc.
  const double k = std::tan(std::numbers::pi * cutoff_hz / sample_rate_hz);
  const double k2 = k * k;
  const int n = order;
  for (int i = 0; i < n / 2; ++i) {
    // Conjugate pole pair i of the normalised analog prototype: s^2 + 2 zeta s + 1 with
    // 2 zeta = 2 sin(pi (2i + 1) / 2n).
    const double two_zeta = 2.0 * std::sin(std::numbers::pi * (2.0 * i + 1.0) / (2.0 * n));
    const double norm = 1.0 / (1.0 + two_zeta * k + k2);
    Biquad s{};
    s.b0 = k2 * norm;
    s.b1 = 2.0 * s.b0;
    s.b2 = s.b0;
    s.a1 = 2.0 * (k2 - 1.0) * norm;
    s.a2 = (1.0 - two_zeta * k + k2) * norm;
    sections_.push_back(s);
  }
}

void ButterworthLowPass::reset(double x) {
  // Each section has unit DC gain, so in steady state every section sees x and outputs x.
  for (Biquad& s : sections_) {
    s.z2 = (s.b2 - s.a2) * x;
    s.z1 = (s.b1 - s.a1) * x + s.z2;
  }
}

double ButterworthLowPass::noise_equivalent_bandwidth_hz() const {
  const double a = std::numbers::pi / (2.0 * order_);
  return cutoff_hz_ * a / std::sin(a);
}

double ButterworthLowPass::white_noise_power_gain() const {
  ButterworthLowPass impulse = *this;
  impulse.reset(0.0);
  double sum = 0.0;
  // The state carries everything still to come out, so once its energy is a negligible
  // fraction of what has come out the tail cannot change the sum. The filter is stable, so the
  // loop ends; the cap only guards against a broken invariant.
  for (long k = 0; k < (1L << 34); ++k) {
    const double y = impulse.filter(k == 0 ? 1.0 : 0.0);
    sum += y * y;
    double state = 0.0;
    for (const Biquad& s : impulse.sections_) state += s.z1 * s.z1 + s.z2 * s.z2;
    if (k > 4 * order_ && state <= 1e-24 * sum) break;
  }
  return sum;
}

}  // namespace calstand::sim

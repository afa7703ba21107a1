// Overlapping Allan, modified Allan and Hadamard deviations from the cumulative sum of rate data
// (NIST SP 1065, sections 5.2.2, 5.2.5 and 5.2.8), with chi-square confidence intervals.
#include "noise/allan.hpp"

#include <fmt/format.h>

#include <Eigen/Core>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <optional>
#include <stdexcept>

#ifdef __linux__
#include <sys/mman.h>
#endif

#include "core/error.hpp"
#include "core/text.hpp"
#include "noise/edf.hpp"
#include "noise/noise_identification.hpp"

namespace calstand::solver {
namespace {

void add_factor(std::vector<std::size_t>& out, double m, std::size_t max_m) {
  const auto k = static_cast<std::size_t>(std::llround(m));
  if (k >= 1 && k <= max_m) out.push_back(k);
}

// Sum of squared second differences x[i + 2m] - 2 x[i + m] + x[i] over i in [begin, end).
// Eigen's array expression is vectorised at the default -O2 (a hand-unrolled loop is not).
double second_difference_sum(const double* x, std::size_t m, std::size_t begin, std::size_t end) {
  const auto len = static_cast<Eigen::Index>(end - begin);
  const Eigen::Map<const Eigen::ArrayXd> a(x + begin, len);
  const Eigen::Map<const Eigen::ArrayXd> b(x + begin + m, len);
  const Eigen::Map<const Eigen::ArrayXd> c(x + begin + 2 * m, len);
  return (c - 2.0 * b + a).square().sum();
}

// Overlapping Allan variance: sum of squared second differences of the phase, stride 1.
double allan_sum(std::span<const double> x, std::size_t m) {
  const std::size_t terms = x.size() - 2 * m;
  const double md = static_cast<double>(m);
  return second_difference_sum(x.data(), m, 0, terms) /
         (2.0 * md * md * static_cast<double>(terms));
}

// Overlapping Allan variances at every m of `ms` in one pass over the phase, block by block:
// the data are far larger than the caches, and one pass per tau would read x[i] from memory
// once per tau; here each block of x[i] is read once and stays in cache for all taus (about
// half the memory traffic, and the sums are memory bound).
std::vector<double> allan_sums_blocked(std::span<const double> x,
                                       const std::vector<std::size_t>& ms) {
  constexpr std::size_t kBlock = 2048;  // 16 KB of x[i]: stays in L1 across the taus
  std::vector<double> sums(ms.size(), 0.0);
  for (std::size_t begin = 0; begin < x.size(); begin += kBlock) {
    for (std::size_t k = 0; k < ms.size(); ++k) {
      const std::size_t terms = x.size() - 2 * ms[k];
      if (begin >= terms) continue;
      sums[k] += second_difference_sum(x.data(), ms[k], begin, std::min(begin + kBlock, terms));
    }
  }
  for (std::size_t k = 0; k < ms.size(); ++k) {
    const double md = static_cast<double>(ms[k]);
    sums[k] /= 2.0 * md * md * static_cast<double>(x.size() - 2 * ms[k]);
  }
  return sums;
}

// Modified Allan variance: the second differences summed over a sliding window of m, squared.
double modified_sum(std::span<const double> x, std::size_t m) {
  const std::size_t n = x.size();
  const std::size_t terms = n - 3 * m + 1;
  const auto d = [&](std::size_t i) { return x[i + 2 * m] - 2.0 * x[i + m] + x[i]; };
  double window = 0.0;
  for (std::size_t i = 0; i < m; ++i) window += d(i);
  double sum = window * window;
  for (std::size_t j = 1; j < terms; ++j) {
    window += d(j + m - 1) - d(j - 1);
    sum += window * window;
  }
  const double md = static_cast<double>(m);
  return sum / (2.0 * md * md * md * md * static_cast<double>(terms));
}

// Overlapping Hadamard variance: third differences of the phase, stride 1.
double hadamard_sum(std::span<const double> x, std::size_t m) {
  const std::size_t terms = x.size() - 3 * m;
  double sum = 0.0;
  for (std::size_t i = 0; i < terms; ++i) {
    const double d = x[i + 3 * m] - 3.0 * x[i + 2 * m] + 3.0 * x[i + m] - x[i];
    sum += d * d;
  }
  const double md = static_cast<double>(m);
  return sum / (6.0 * md * md * static_cast<double>(terms));
}

// Non-overlapping Hadamard variance: third differences starting every m samples.
double hadamard_plain_sum(std::span<const double> x, std::size_t m) {
  const std::size_t terms = (x.size() - 1) / m - 2;
  double sum = 0.0;
  for (std::size_t k = 0; k < terms; ++k) {
    const std::size_t i = k * m;
    const double d = x[i + 3 * m] - 3.0 * x[i + 2 * m] + 3.0 * x[i + m] - x[i];
    sum += d * d;
  }
  const double md = static_cast<double>(m);
  return sum / (6.0 * md * md * static_cast<double>(terms));
}

std::size_t term_count(AllanKind kind, std::size_t phase_points, std::size_t m) {
  switch (kind) {
    case AllanKind::kAllan:
      return phase_points - 2 * m;
    case AllanKind::kModified:
      return phase_points - 3 * m + 1;
    case AllanKind::kHadamard:
      return phase_points - 3 * m;
    case AllanKind::kHadamardNonOverlapping:
      return (phase_points - 1) / m - 2;
  }
  return 0;
}

// The degrees of freedom of phase noise, bounded by the data length.
//
// Phase noise (white or flicker PM, alpha 2 or 1) is the one case in which the EDF of the
// overlapping estimators grows with the number of samples N and not with the record's length
// T in units of tau: white PM's phase points are independent, so the overlapping differences
// at tau are nearly independent at every start sample and EDF ~ N / 2 however long tau is
// (NIST SP 1065 Table 5, Howe's white-PM form; Greenhall and Riley, PTTI 2003). Frequency
// noise (alpha <= 0) is correlated over tau instead: the record holds only T / tau = N / m
// independent spans of tau, and overlapping them gains at most a factor of about 3/2, for
// white FM (EDF ~ 3 N / (2 m), SP 1065 Table 5), less for flicker and random-walk FM.
//
// A curve is rarely pure phase noise at its longer taus: frequency noise takes a growing share
// q of the variance there (a phase-to-frequency transition). For independent noises a + b the
// estimate s^2 = mean((a + b)^2) has Var = Var(mean a^2) + Var(mean b^2) + 4 Var(mean ab)
// (the other covariances vanish), so Var(s^2) >= Var(s_b^2) = 2 (q sigma^2)^2 / edf_b, and with
// edf = 2 sigma^4 / Var(s^2): edf <= edf_b / q^2 <= edf_whiteFM(m, N) / q^2. That is the
// bound applied to a phase-noise point: the data length (through white FM's EDF) divided by
// the squared frequency-noise share.
//
// Where the lag-1 method identified phase noise, the share comes from the local slope mu,
// which moves from the phase-noise slope towards white FM's (-1) as frequency noise mixes in:
// q = (mu - mu_phase) / (-1 - mu_phase), clamped to [0, 1]. Pure phase noise (q near 0) keeps
// its EDF. The method names the dominant power law of the decimated phase, so it still calls
// a tau white or flicker PM while frequency noise holds a fair share of the variance (on white
// PM plus white FM, flicker PM up to a share of about a half): without the bound a record of
// 65,536 s with the change at 8192 s gets white PM's EDF, 32,000, at 2048 s, where the share
// (20 %) allows 1144 at most (tests/unit/noise/allan_test.cpp). Unlike the slope-identified types
// this bound once served, an identified type is not bounded further where a neighbouring tau is
// frequency noise: on allantools' Cs 5071A record that rule cut Stable32's flicker-PM EDF at 100 s
// (+-0.37 %) to white FM's (+-0.77 %) because 200 s is white FM, though the slope there gives a
// share of 15 to 17 %.
//
// Where the method could not identify (fewer than 30 decimated points, the last octave or so)
// and phase noise is carried from a shorter tau, nothing tells the share: the slope at the
// end of a curve is that of a handful of spans, and carried types are all alike, so the
// neighbours tell nothing either. q = 1 there: white FM's EDF (about 1.5 times the fewer than
// 30 spans of tau) caps the phase-noise one. Without it the same record gave EDF 22,700 at
// 16,384 s, where frequency noise is two thirds of the variance and 9 is the most it allows.
double frequency_noise_share(const std::vector<AllanPoint>& points,
                             const std::vector<double>& slopes, std::size_t k, AllanKind kind,
                             bool carried) {
  if (carried) return 1.0;
  // The slope of the phase noise named: -2 on the Allan and Hadamard curves (white and
  // flicker PM alike); on the modified curve -3 for white PM, -2 for flicker PM.
  const double mu_phase = kind == AllanKind::kModified && points[k].alpha == 2 ? -3.0 : -2.0;
  return std::clamp((slopes[k] - mu_phase) / (-1.0 - mu_phase), 0.0, 1.0);
}

// Log-log slope of the variance at point k: least squares over the points within a factor of 2
// in tau (the immediate neighbours when there are none), skipping zero variances. A single
// neighbour pair of a dense tau set is a tenth of a decade apart, far too noisy a slope.
double local_slope(const std::vector<std::size_t>& ms, const std::vector<double>& var,
                   std::size_t k) {
  const double centre = std::log(static_cast<double>(ms[k]));
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0, n = 0.0;
  const auto add = [&](std::size_t j) {
    if (var[j] <= 0.0) return;
    const double x = std::log(static_cast<double>(ms[j])) - centre;
    const double y = std::log(var[j]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    n += 1.0;
  };
  for (std::size_t j = 0; j < ms.size(); ++j) {
    if (std::abs(std::log(static_cast<double>(ms[j])) - centre) <= std::log(2.0) + 1e-9) add(j);
  }
  if (n < 2.0 || sxx * n - sx * sx <= 0.0) {
    sx = sy = sxx = sxy = n = 0.0;
    if (k > 0) add(k - 1);
    add(k);
    if (k + 1 < ms.size()) add(k + 1);
  }
  const double det = n * sxx - sx * sx;
  return n >= 2.0 && det > 0.0 ? (n * sxy - sx * sy) / det : 0.0;
}

// Writes the phase of `rate` (see phase_from_rate()) to x[0 .. rate.size()].
void fill_phase(std::span<const double> rate, double* x) {
  double mean = 0.0;
  for (std::size_t i = 0; i < rate.size(); ++i) {
    if (!std::isfinite(rate[i])) {
      throw core::InputError("data", fmt::format("sample {} is not finite ({})", i, rate[i]));
    }
    mean += rate[i];
  }
  mean /= static_cast<double>(std::max<std::size_t>(rate.size(), 1));
  // A plain running sum: with the mean removed the phase is a zero-mean walk, and its rounding
  // error (about eps sqrt(n) |x|) is some 1e-10 of a sample's noise even at millions of
  // samples; a residual error in the mean adds a linear phase ramp, which every estimator here
  // cancels exactly.
  x[0] = 0.0;
  double sum = 0.0;
  for (std::size_t i = 0; i < rate.size(); ++i) {
    sum += rate[i] - mean;
    x[i + 1] = sum;
  }
}

// A buffer for the phase of a long record. At 5.4 million samples (12 h at 125 Hz) it is
// 43 MB, and faulting that in 4 KB pages took longer than all the Allan sums; on Linux it is
// asked for in transparent huge pages (a hint: without them it is an ordinary allocation).
class PhaseBuffer {
 public:
  explicit PhaseBuffer(std::size_t n) : size_(n) {
    constexpr std::size_t kHuge = std::size_t{2} << 20U;
    const std::size_t bytes = n * sizeof(double);
    if (bytes >= kHuge) {
      const std::size_t rounded = (bytes + kHuge - 1) / kHuge * kHuge;
      data_ = static_cast<double*>(std::aligned_alloc(kHuge, rounded));
#ifdef __linux__
      if (data_) madvise(data_, rounded, MADV_HUGEPAGE);
#endif
    } else {
      data_ = static_cast<double*>(std::malloc(std::max<std::size_t>(bytes, sizeof(double))));
    }
    if (!data_) throw std::bad_alloc();
  }
  ~PhaseBuffer() { std::free(data_); }
  PhaseBuffer(const PhaseBuffer&) = delete;
  PhaseBuffer& operator=(const PhaseBuffer&) = delete;
  double* data() { return data_; }
  std::span<const double> span() const { return {data_, size_}; }

 private:
  std::size_t size_;
  double* data_ = nullptr;
};

}  // namespace

std::string_view to_string(AllanKind kind) {
  switch (kind) {
    case AllanKind::kAllan:
      return "adev";
    case AllanKind::kModified:
      return "mdev";
    case AllanKind::kHadamard:
      return "ohdev";
    case AllanKind::kHadamardNonOverlapping:
      return "hdev";
  }
  return "?";
}

AllanKind parse_allan_kind(std::string_view text) {
  if (text == "adev") return AllanKind::kAllan;
  if (text == "mdev") return AllanKind::kModified;
  if (text == "ohdev") return AllanKind::kHadamard;
  if (text == "hdev") return AllanKind::kHadamardNonOverlapping;
  throw core::InputError("kind", fmt::format("'{}' is not adev, mdev, ohdev or hdev", text));
}

TauSet TauSet::parse(std::string_view text) {
  const std::string_view t = core::trim_blanks(text);
  if (t == "octave") return {TauSpacing::kOctave, {}};
  if (t == "decade") return {TauSpacing::kDecade, {}};
  if (t == "dense") return {TauSpacing::kDense, {}};
  TauSet set{TauSpacing::kExplicit, {}};
  std::string_view rest = t;
  while (true) {
    const std::size_t comma = rest.find(',');
    const std::string_view item = core::trim_blanks(rest.substr(0, comma));
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(item.data(), item.data() + item.size(), value);
    if (item.empty() || ec != std::errc() || ptr != item.data() + item.size() ||
        !std::isfinite(value) || value <= 0.0) {
      throw core::InputError(
          "taus", fmt::format("'{}': expected octave, decade, dense or a comma-separated list of "
                              "positive averaging times in seconds; bad entry '{}'",
                              text, item));
    }
    set.taus_s.push_back(value);
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  return set;
}

std::size_t max_averaging_factor(AllanKind kind, std::size_t samples) {
  return kind == AllanKind::kAllan ? samples / 2 : samples / 3;
}

std::vector<std::size_t> averaging_factors(const TauSet& taus, std::size_t samples,
                                           double sample_rate_hz, AllanKind kind) {
  const std::size_t max_m = max_averaging_factor(kind, samples);
  std::vector<std::size_t> out;
  switch (taus.spacing) {
    case TauSpacing::kOctave:
      for (std::size_t m = 1; m <= max_m; m *= 2) out.push_back(m);
      break;
    case TauSpacing::kDecade:
      for (std::size_t m = 1; m <= max_m; m *= 10) out.push_back(m);
      break;
    case TauSpacing::kDense:
      for (int k = 0;; ++k) {
        const double m = std::pow(10.0, k / 10.0);
        if (std::llround(m) > static_cast<long long>(max_m)) break;
        add_factor(out, m, max_m);
      }
      break;
    case TauSpacing::kExplicit: {
      if (taus.taus_s.empty())
        throw core::InputError("taus", "the list of averaging times is empty");
      const double dt = 1.0 / sample_rate_hz;
      for (const double tau : taus.taus_s) {
        const double m = tau * sample_rate_hz;
        if (!std::isfinite(m) || m < 0.5 || std::llround(m) > static_cast<long long>(max_m)) {
          throw core::InputError(
              "taus", fmt::format("averaging time {} s is outside [{} s, {} s], the range {} "
                                  "samples at {} Hz allow for {}",
                                  tau, dt, static_cast<double>(max_m) * dt, samples, sample_rate_hz,
                                  to_string(kind)));
        }
        add_factor(out, m, max_m);
      }
      break;
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  if (out.empty()) {
    throw core::InputError("taus",
                           fmt::format("{} samples are too few for {}", samples, to_string(kind)));
  }
  return out;
}

void AllanOptions::validate() const {
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw core::InputError("confidence", fmt::format("must be in (0, 1), got {}", confidence));
  }
  if (alpha && (*alpha < min_alpha(kind) || *alpha > kMaxAlpha)) {
    throw core::InputError("alpha",
                           fmt::format("noise exponent {} is outside [{}, {}] for {}", *alpha,
                                       min_alpha(kind), kMaxAlpha, to_string(kind)));
  }
  if (taus.spacing == TauSpacing::kExplicit) {
    if (taus.taus_s.empty()) throw core::InputError("taus", "the list of averaging times is empty");
    for (const double t : taus.taus_s) {
      if (!std::isfinite(t) || t <= 0.0) {
        throw core::InputError("taus", fmt::format("averaging time {} s is not positive", t));
      }
    }
  }
}

std::vector<double> phase_from_rate(std::span<const double> rate) {
  std::vector<double> x(rate.size() + 1);
  fill_phase(rate, x.data());
  return x;
}

double allan_variance_from_phase(std::span<const double> phase, std::size_t m, AllanKind kind) {
  const std::size_t samples = phase.empty() ? 0 : phase.size() - 1;
  if (m == 0 || m > max_averaging_factor(kind, samples)) {
    throw core::InputError("m", fmt::format("averaging factor {} is outside [1, {}] for {} samples",
                                            m, max_averaging_factor(kind, samples), samples));
  }
  switch (kind) {
    case AllanKind::kAllan:
      return allan_sum(phase, m);
    case AllanKind::kModified:
      return modified_sum(phase, m);
    case AllanKind::kHadamard:
      return hadamard_sum(phase, m);
    case AllanKind::kHadamardNonOverlapping:
      return hadamard_plain_sum(phase, m);
  }
  return 0.0;
}

AllanResult allan(std::span<const double> rate, double sample_rate_hz,
                  const AllanOptions& options) {
  options.validate();
  if (!std::isfinite(sample_rate_hz) || sample_rate_hz <= 0.0) {
    throw core::InputError("sample_rate_hz",
                           fmt::format("must be positive and finite, got {}", sample_rate_hz));
  }
  const std::size_t min_samples = options.kind == AllanKind::kAllan ? 2 : 3;
  if (rate.size() < min_samples) {
    throw core::InputError("data", fmt::format("{} samples; {} needs at least {}", rate.size(),
                                               to_string(options.kind), min_samples));
  }
  const std::vector<std::size_t> ms =
      averaging_factors(options.taus, rate.size(), sample_rate_hz, options.kind);
  PhaseBuffer buffer(rate.size() + 1);
  fill_phase(rate, buffer.data());
  const std::span<const double> x = buffer.span();

  std::vector<double> var(ms.size());
  std::vector<std::size_t> terms(ms.size());
  if (options.kind == AllanKind::kAllan) var = allan_sums_blocked(x, ms);
  for (std::size_t k = 0; k < ms.size(); ++k) {
    if (options.kind != AllanKind::kAllan)
      var[k] = allan_variance_from_phase(x, ms[k], options.kind);
    terms[k] = term_count(options.kind, x.size(), ms[k]);
  }
  // The noise type at each m by the lag-1 autocorrelation of the decimated phase (Riley and
  // Greenhall 2004, as Stable32 and the total deviations do), and at the longest octave factor
  // it can identify, carried to the taus beyond (see allan_result_from_variances).
  std::vector<std::optional<int>> identified;
  std::optional<int> carried;
  if (options.intervals && !options.alpha) {
    const int dmax = difference_order(options.kind);
    const auto identify_at = [&](std::size_t m) -> std::optional<int> {
      if (rate.size() / m + 1 < kLag1MinPoints) return std::nullopt;
      Lag1Accumulator acc(dmax);
      acc.push(x.data(), (x.size() - 1) / m + 1, m, 0.0);
      const auto id = acc.identify(dmax, min_alpha(options.kind));
      return id ? std::optional<int>(id->alpha) : std::nullopt;
    };
    for (const std::size_t m : ms) identified.push_back(identify_at(m));
    const std::size_t longest = lag1_longest_octave_factor(rate.size());
    if (longest > 0) {
      const auto it = std::find(ms.begin(), ms.end(), longest);
      carried = it != ms.end() ? identified[static_cast<std::size_t>(it - ms.begin())]
                               : identify_at(longest);
    }
  }
  return allan_result_from_variances(ms, var, terms, rate.size(), sample_rate_hz, options,
                                     identified, carried);
}

AllanResult allan_result_from_variances(std::span<const std::size_t> ms,
                                        std::span<const double> var,
                                        std::span<const std::size_t> terms, std::size_t samples,
                                        double sample_rate_hz, const AllanOptions& options,
                                        std::span<const std::optional<int>> identified,
                                        std::optional<int> carried) {
  if (options.intervals && !options.alpha && identified.size() != ms.size()) {
    throw std::logic_error(fmt::format("{} noise types identified for {} averaging factors",
                                       identified.size(), ms.size()));
  }
  AllanResult result;
  result.kind = options.kind;
  result.sample_rate_hz = sample_rate_hz;
  result.samples = samples;
  result.confidence = options.confidence;
  const std::vector<std::size_t> msv(ms.begin(), ms.end());
  const std::vector<double> varv(var.begin(), var.end());
  for (std::size_t k = 0; k < ms.size(); ++k) {
    AllanPoint p;
    p.m = ms[k];
    p.tau_s = static_cast<double>(ms[k]) / sample_rate_hz;
    p.deviation = std::sqrt(var[k]);
    p.terms = terms[k];
    result.points.push_back(p);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> slopes(ms.size(), nan);
  std::vector<char> is_carried(ms.size(), 0);
  for (std::size_t k = 0; k < ms.size(); ++k) {
    AllanPoint& p = result.points[k];
    if (!options.intervals) {
      p.edf = p.lo = p.hi = nan;
      continue;
    }
    if (options.alpha) {
      p.alpha = *options.alpha;
    } else {
      slopes[k] = local_slope(msv, varv, k);
      if (identified[k]) {
        p.alpha = *identified[k];
      } else {
        // Too few decimated points (or constant data): the type identified at the longest
        // octave tau the method reaches, white FM if it found none.
        p.alpha = carried.value_or(0);
        is_carried[k] = 1;
      }
    }
  }
  for (std::size_t k = 0; k < ms.size() && options.intervals; ++k) {
    AllanPoint& p = result.points[k];
    p.edf = equivalent_dof(options.kind, p.alpha, p.m, samples);
    if (!options.alpha && p.alpha >= 1) {
      // Phase noise: bounded by the data length and the frequency-noise share (see above).
      const double q =
          frequency_noise_share(result.points, slopes, k, options.kind, is_carried[k] != 0);
      if (q > 0.0) {
        p.edf = std::min(p.edf, equivalent_dof(options.kind, 0, p.m, samples) / (q * q));
      }
    }
    const DeviationInterval ci = deviation_interval(p.deviation, p.edf, options.confidence);
    p.lo = ci.lo;
    p.hi = ci.hi;
  }
  return result;
}

}  // namespace calstand::solver

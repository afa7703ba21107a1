// Total and Theo deviations (NIST SP 1065 sections 5.2.11 to 5.2.15), their bias corrections
// as Stable32 applies them and their degrees of freedom (SP 1065 section 5.3.3).
#include "noise/total_deviation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "core/error.hpp"
#include "noise/edf.hpp"
#include "noise/noise_identification.hpp"

namespace calstand::solver {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// TOTVAR bias, E[TOTVAR] = AVAR (1 - a tau / T) (Howe, "Total variance explained", 1999,
// Table 1; SP 1065 eq. 26): a = 1 / (3 ln 2) for flicker FM, 3/4 for random-walk FM.
double totvar_bias_a(int alpha) {
  if (alpha == -1) return 1.0 / (3.0 * std::log(2.0));
  if (alpha == -2) return 0.75;
  return 0.0;
}

// HTOTVAR bias, E[HTOT] = HVAR (1 + a) (Howe et al., "A total estimator of the Hadamard
// function used for GPS operations", PTTI 2000, Table 1; SP 1065 section 5.2.15).
double htotvar_bias_a(int alpha) {
  switch (alpha) {
    case 0:
      return -0.005;
    case -1:
      return -0.149;
    case -2:
      return -0.229;
    case -3:
      return -0.283;
    case -4:
      return -0.321;
    default:
      return 0.0;
  }
}

// Theo1 bias AVAR/Theo1 = a + b / (0.75 m)^c (Howe and Tasset, "Theo1: characterization of
// very long-term frequency stability", EFTF 2004, Table 1; SP 1065 section 5.2.14).
struct Theo1Bias {
  double a, b, c;
};
Theo1Bias theo1_bias_coefficients(int alpha) {
  switch (alpha) {
    case 2:
      return {0.09, 0.74, 0.40};
    case 1:
      return {0.14, 0.82, 0.30};
    case -1:
      return {1.87, -1.05, 0.79};
    case -2:
      return {2.70, -1.53, 0.85};
    default:
      return {1.0, 0.0, 0.0};
  }
}

// EDF = b (T / tau) - c of TOTVAR and of MTOTVAR/TTOTVAR (SP 1065 Tables 10 and 11, from Howe's
// and Howe and Vernotte's papers); false where the tables have no row for alpha.
bool totvar_edf_coefficients(int alpha, double& b, double& c) {
  switch (alpha) {
    case 0:
      b = 1.50, c = 0.0;
      return true;
    case -1:
      b = 1.17, c = 0.22;
      return true;
    case -2:
      b = 0.93, c = 0.36;
      return true;
    default:
      return false;
  }
}
bool mtotvar_edf_coefficients(int alpha, double& b, double& c) {
  switch (alpha) {
    case 2:
      b = 1.90, c = 2.10;
      return true;
    case 1:
      b = 1.20, c = 1.40;
      return true;
    case 0:
      b = 1.10, c = 1.20;
      return true;
    case -1:
      b = 0.85, c = 0.50;
      return true;
    case -2:
      b = 0.75, c = 0.31;
      return true;
    default:
      return false;
  }
}
// HTOTVAR: EDF = (T / tau) / (b0 + b1 tau / T) for white to random-run FM (SP 1065 Table 12).
bool htotvar_edf_coefficients(int alpha, double& b0, double& b1) {
  switch (alpha) {
    case 0:
      b0 = 0.559, b1 = 1.004;
      return true;
    case -1:
      b0 = 0.868, b1 = 1.140;
      return true;
    case -2:
      b0 = 0.938, b1 = 1.696;
      return true;
    case -3:
      b0 = 0.974, b1 = 2.554;
      return true;
    case -4:
      b0 = 1.276, b1 = 3.149;
      return true;
    default:
      return false;
  }
}

// Theo1 EDF (Howe and Peppler, "Estimation of very long-term frequency stability using a
// special-purpose statistic", 2003; SP 1065 Table 8), with t = 0.75 m and N phase points.
double theo1_edf(int alpha, double n, double t) {
  switch (alpha) {
    case 2:
      return (0.86 * (n + 1.0) * (n - 4.0 * t / 3.0)) / (n - t) * (t / (t + 1.14));
    case 1:
      return (4.798 * n * n - 6.374 * n * t + 12.387 * t) / (std::sqrt(t + 36.6) * (n - t)) *
             (t / (t + 0.3));
    case 0:
      return ((4.1 * n + 0.8) / t - (3.1 * n + 6.5) / n) *
             (std::pow(t, 1.5) / (std::pow(t, 1.5) + 5.2));
    case -1:
      return (2.0 * n * n - 1.3 * n * t - 3.5 * t) / (n * t) * (t * t * t / (t * t * t + 2.3));
    default: {  // -2
      const double a = 4.4 * n;
      return (a - 2.0) / (2.9 * t) *
             (((a - 1.0) * (a - 1.0) - 8.6 * t * (a - 1.0) + 11.4 * t * t) /
              ((a - 3.0) * (a - 3.0)));
    }
  }
}

// MTOTVAR bias, E[MTOT] = MVAR * ratio (Howe and Vernotte, PTTI 1999; SP 1065 section 5.2.12).
// Stable32 does not apply it (its MTOTDEV of PHASE.DAT is the raw estimate at alpha 0 and 1
// alike); SP 1065's test-set table (section 12.5) does, at white FM.
double mtotvar_bias_ratio(int alpha) {
  switch (alpha) {
    case 2:
      return 0.94;
    case 1:
      return 0.83;
    case 0:
      return 0.73;
    case -1:
      return 0.70;
    default:
      return 0.69;
  }
}

bool is_theo(TotalKind kind) { return kind == TotalKind::kTheo1 || kind == TotalKind::kTheoBr; }

// The estimator behind each kind at a point: TheoH switches between Allan and TheoBR.
enum class Estimator { kTotal, kModifiedTotal, kHadamardTotal, kTheo1, kTheoBr, kAllan };

// ---- the variances, in the squared unit of the rate; x is the phase in rate * samples ----

// Reflected phase x*: odd reflection about each end (SP 1065 eq. 25).
double reflected(std::span<const double> x, std::ptrdiff_t k) {
  const auto n = static_cast<std::ptrdiff_t>(x.size());
  if (k < 0) return 2.0 * x[0] - x[static_cast<std::size_t>(-k)];
  if (k >= n)
    return 2.0 * x[static_cast<std::size_t>(n - 1)] - x[static_cast<std::size_t>(2 * (n - 1) - k)];
  return x[static_cast<std::size_t>(k)];
}

double totvar(std::span<const double> x, std::size_t m) {
  const auto n = static_cast<std::ptrdiff_t>(x.size());
  const auto mm = static_cast<std::ptrdiff_t>(m);
  double sum = 0.0;
  for (std::ptrdiff_t i = 1; i <= n - 2; ++i) {
    const double d =
        reflected(x, i - mm) - 2.0 * x[static_cast<std::size_t>(i)] + reflected(x, i + mm);
    sum += d * d;
  }
  const double md = static_cast<double>(m);
  return sum / (2.0 * md * md * static_cast<double>(n - 2));
}

// The 3m-point run xs (m >= 1) with its linear trend removed by the half averages (the slope
// between the means of the first and the last half), extended by even reflection to 9m
// points (flip, run, flip), then the mean over its 6m windows of the squared second difference
// of three adjacent m-point averages: the inner part of MTOTVAR and HTOTVAR (SP 1065 eq. 27
// and section 5.2.15).
double reflected_run_mean_square(const double* xs, std::size_t m, std::vector<double>& star) {
  const std::size_t len = 3 * m;
  const std::size_t half = len / 2;
  double mean1 = 0.0, mean2 = 0.0;
  for (std::size_t j = 0; j < half; ++j) mean1 += xs[j];
  for (std::size_t j = len - half; j < len; ++j) mean2 += xs[j];
  mean1 /= static_cast<double>(half);
  mean2 /= static_cast<double>(half);
  // The two halves' centres are (len + 1) / 2 apart when len is odd (the middle point is in
  // neither), len / 2 apart when it is even.
  const double span = len % 2 == 1 ? static_cast<double>(half + 1) : static_cast<double>(half);
  const double slope = (mean2 - mean1) / span;
  star.resize(9 * m);
  for (std::size_t j = 0; j < len; ++j) {
    const double v = xs[j] - slope * static_cast<double>(j);
    star[len + j] = v;
    star[len - 1 - j] = v;
    star[3 * len - 1 - j] = v;
  }
  double s1 = 0.0, s2 = 0.0, s3 = 0.0;
  for (std::size_t j = 0; j < m; ++j) {
    s1 += star[j];
    s2 += star[m + j];
    s3 += star[2 * m + j];
  }
  const double md = static_cast<double>(m);
  double sum = 0.0;
  for (std::size_t j = 0; j < 6 * m; ++j) {
    if (j > 0) {
      s1 += star[j + m - 1] - star[j - 1];
      s2 += star[j + 2 * m - 1] - star[j + m - 1];
      s3 += star[j + 3 * m - 1] - star[j + 2 * m - 1];
    }
    const double d = (s1 - 2.0 * s2 + s3) / md;
    sum += d * d;
  }
  return sum / (6.0 * md);
}

double mtotvar(std::span<const double> x, std::size_t m) {
  const std::size_t runs = x.size() - 3 * m + 1;
  std::vector<double> star;
  double sum = 0.0;
  for (std::size_t i = 0; i < runs; ++i) sum += reflected_run_mean_square(x.data() + i, m, star);
  const double md = static_cast<double>(m);
  return sum / (2.0 * md * md * static_cast<double>(runs));
}

// HTOTVAR on the rate y = diff(x): at m = 1 the overlapping Hadamard variance, as Stable32
// (Howe et al. 2000: "for best consistency"); above, the runs of 3m rate points detrended and
// reflected as for MTOTVAR, the Hadamard variance of each run being its mean square over 6.
double htotvar(std::span<const double> x, std::size_t m) {
  if (m == 1) return allan_variance_from_phase(x, 1, AllanKind::kHadamard);
  std::vector<double> y(x.size() - 1);
  for (std::size_t i = 0; i + 1 < x.size(); ++i) y[i] = x[i + 1] - x[i];
  const std::size_t runs = y.size() - 3 * m + 1;
  std::vector<double> star;
  double sum = 0.0;
  for (std::size_t i = 0; i < runs; ++i) sum += reflected_run_mean_square(y.data() + i, m, star);
  return sum / (6.0 * static_cast<double>(runs));
}

// Theo1 (SP 1065 eq. 30): m even, tau = 0.75 m.
double theo1var(std::span<const double> x, std::size_t m) {
  const std::size_t n = x.size();
  const std::size_t h = m / 2;
  double sum = 0.0;
  for (std::size_t i = 0; i < n - m; ++i) {
    double s = 0.0;
    for (std::size_t d = 0; d < h; ++d) {
      const double v = x[i] - x[i + h - d] + x[i + m] - x[i + h + d];
      s += v * v / static_cast<double>(h - d);
    }
    sum += s;
  }
  const double md = static_cast<double>(m);
  return sum / (0.75 * static_cast<double>(n - m) * md * md);
}

std::size_t max_m(Estimator e, std::size_t n) {
  switch (e) {
    case Estimator::kTotal:
      return (n - 1) / 2;  // tau up to T / 2, where the TOTVAR bias model holds
    case Estimator::kModifiedTotal:
      return n / 3;
    case Estimator::kHadamardTotal:
      return (n - 1) / 3;
    case Estimator::kAllan:
      return (n - 1) / 2;
    case Estimator::kTheo1:
    case Estimator::kTheoBr:
      return (n - 1) / 2 * 2;  // m even, m <= N - 1
  }
  return 0;
}

std::size_t term_count(Estimator e, std::size_t n, std::size_t m) {
  switch (e) {
    case Estimator::kTotal:
      return n - 2;
    case Estimator::kModifiedTotal:
      return n - 3 * m + 1;
    case Estimator::kHadamardTotal:
      return m == 1 ? n - 3 : n - 3 * m;  // rate runs: (n - 1) - 3m + 1
    case Estimator::kAllan:
      return n - 2 * m;
    case Estimator::kTheo1:
    case Estimator::kTheoBr:
      return (n - m) * (m / 2);
  }
  return 0;
}

Estimator estimator_of(TotalKind kind) {
  switch (kind) {
    case TotalKind::kTotal:
      return Estimator::kTotal;
    case TotalKind::kModifiedTotal:
    case TotalKind::kTimeTotal:
      return Estimator::kModifiedTotal;
    case TotalKind::kHadamardTotal:
      return Estimator::kHadamardTotal;
    case TotalKind::kTheo1:
      return Estimator::kTheo1;
    case TotalKind::kTheoBr:
    case TotalKind::kTheoH:
      return Estimator::kTheoBr;
  }
  return Estimator::kTotal;
}

// One requested point: the estimator and its averaging factor.
struct Plan {
  Estimator estimator;
  std::size_t m;
};

std::size_t nearest_even(double v) {
  const auto k = static_cast<std::size_t>(std::max(1.0, std::round(v / 2.0)));
  return 2 * k;
}

// Averaging times in samples requested by `taus` between lo and hi (in samples of tau).
std::vector<double> requested_taus(const TauSet& taus, double lo, double hi, double rate_hz,
                                   bool theo) {
  std::vector<double> out;
  switch (taus.spacing) {
    case TauSpacing::kOctave:
      for (double t = lo; t <= hi * (1 + 1e-12); t *= 2.0) out.push_back(t);
      break;
    case TauSpacing::kDecade:
      for (double t = theo ? 7.5 : 1.0; t <= hi * (1 + 1e-12); t *= 10.0) {
        if (t >= lo * (1 - 1e-12)) out.push_back(t);
      }
      break;
    case TauSpacing::kDense:
      for (int k = 0;; ++k) {
        const double t = lo * std::pow(10.0, k / 10.0);
        if (t > hi * (1 + 1e-12)) break;
        out.push_back(t);
      }
      break;
    case TauSpacing::kExplicit:
      for (double s : taus.taus_s) {
        const double t = s * rate_hz;
        if (t < lo * (1 - 1e-9) - 0.5 || t > hi * (1 + 1e-9) + 0.5) {
          throw core::InputError(
              "taus", fmt::format("tau {} s is outside the range this estimator can evaluate on "
                                  "the record, {:.6g} s to {:.6g} s",
                                  s, lo / rate_hz, hi / rate_hz));
        }
        out.push_back(t);
      }
      break;
  }
  return out;
}

std::vector<Plan> plan_points(const TotalOptions& o, std::size_t n, double rate_hz) {
  std::vector<Plan> plan;
  const auto add = [&](Estimator e, std::size_t m) {
    if (m < 1 || m > max_m(e, n)) return;
    for (const Plan& p : plan) {
      if (p.estimator == e && p.m == m) return;
    }
    plan.push_back({e, m});
  };
  const Estimator e = estimator_of(o.kind);
  if (o.kind == TotalKind::kTheoH) {
    // AVAR up to k, the largest tau within 10 % of the record T = (N - 1) tau0; TheoBR from
    // tau = 0.75 m >= k on (SP 1065 eq. 33).
    const double t_record = static_cast<double>(n - 1);
    const std::size_t k = std::max<std::size_t>(1, static_cast<std::size_t>(0.1 * t_record));
    for (double t :
         requested_taus(o.taus, 1.0, 0.75 * static_cast<double>(max_m(e, n)), rate_hz, false)) {
      if (t < static_cast<double>(k) - 1e-9) {
        add(Estimator::kAllan, static_cast<std::size_t>(std::llround(t)));
      } else {
        std::size_t m = nearest_even(t / 0.75);
        while (0.75 * static_cast<double>(m) < static_cast<double>(k)) m += 2;
        add(Estimator::kTheoBr, m);
      }
    }
  } else if (is_theo(o.kind)) {
    for (double t :
         requested_taus(o.taus, 1.5, 0.75 * static_cast<double>(max_m(e, n)), rate_hz, true)) {
      add(e, nearest_even(t / 0.75));
    }
  } else {
    for (double t : requested_taus(o.taus, 1.0, static_cast<double>(max_m(e, n)), rate_hz, false)) {
      add(e, static_cast<std::size_t>(std::max<long long>(1, std::llround(t))));
    }
  }
  std::sort(plan.begin(), plan.end(), [](const Plan& a, const Plan& b) {
    const double ta = (a.estimator == Estimator::kTheo1 || a.estimator == Estimator::kTheoBr)
                          ? 0.75 * static_cast<double>(a.m)
                          : static_cast<double>(a.m);
    const double tb = (b.estimator == Estimator::kTheo1 || b.estimator == Estimator::kTheoBr)
                          ? 0.75 * static_cast<double>(b.m)
                          : static_cast<double>(b.m);
    return ta < tb;
  });
  if (plan.empty()) throw core::InputError("taus", "no averaging time fits the record");
  return plan;
}

double raw_variance(std::span<const double> x, Estimator e, std::size_t m) {
  switch (e) {
    case Estimator::kTotal:
      return totvar(x, m);
    case Estimator::kModifiedTotal:
      return mtotvar(x, m);
    case Estimator::kHadamardTotal:
      return htotvar(x, m);
    case Estimator::kTheo1:
    case Estimator::kTheoBr:
      return theo1var(x, m);
    case Estimator::kAllan:
      return allan_variance_from_phase(x, m, AllanKind::kAllan);
  }
  return kNaN;
}

// Noise identification at a point: the lag-1 method on the phase decimated by the tau of the
// point in samples (0.75 m for the Theo kinds, as Stable32 identifies at the displayed tau).
std::optional<int> identify(std::span<const double> x, Estimator e, std::size_t m) {
  const bool hadamard = e == Estimator::kHadamardTotal;
  const bool theo = e == Estimator::kTheo1 || e == Estimator::kTheoBr;
  const std::size_t af =
      theo ? std::max<std::size_t>(
                 1, static_cast<std::size_t>(std::llround(0.75 * static_cast<double>(m))))
           : m;
  const auto id = identify_noise_lag1(x, af, hadamard ? 3 : 2, hadamard ? -4 : -2);
  if (!id) return std::nullopt;
  return id->alpha;
}

}  // namespace

std::string_view to_string(TotalKind kind) {
  switch (kind) {
    case TotalKind::kTotal:
      return "totdev";
    case TotalKind::kModifiedTotal:
      return "mtotdev";
    case TotalKind::kTimeTotal:
      return "ttotdev";
    case TotalKind::kHadamardTotal:
      return "htotdev";
    case TotalKind::kTheo1:
      return "theo1";
    case TotalKind::kTheoBr:
      return "theobr";
    case TotalKind::kTheoH:
      return "theoh";
  }
  return "?";
}

std::optional<TotalKind> parse_total_kind(std::string_view text) {
  for (TotalKind k :
       {TotalKind::kTotal, TotalKind::kModifiedTotal, TotalKind::kTimeTotal,
        TotalKind::kHadamardTotal, TotalKind::kTheo1, TotalKind::kTheoBr, TotalKind::kTheoH}) {
    if (text == to_string(k)) return k;
  }
  return std::nullopt;
}

void TotalOptions::validate() const {
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw core::InputError("confidence", fmt::format("must be in (0, 1), got {}", confidence));
  }
  if (alpha) {
    const int lo = kind == TotalKind::kHadamardTotal ? -4 : -2;
    if (*alpha < lo || *alpha > 2) {
      throw core::InputError(
          "alpha", fmt::format("{} takes alpha in [{}, 2], got {}", to_string(kind), lo, *alpha));
    }
  }
  if (taus.spacing == TauSpacing::kExplicit && taus.taus_s.empty()) {
    throw core::InputError("taus", "the list of averaging times is empty");
  }
}

double total_variance_from_phase(std::span<const double> x, std::size_t m, TotalKind kind) {
  if (kind == TotalKind::kTheoBr || kind == TotalKind::kTheoH) {
    throw core::InputError("kind", "TheoBR and TheoH are whole-record statistics");
  }
  const Estimator e = estimator_of(kind);
  if (x.size() < 8 || m < 1 || m > max_m(e, x.size()) || (e == Estimator::kTheo1 && m % 2 != 0)) {
    throw core::InputError("m", fmt::format("averaging factor {} is out of range for {} on {} "
                                            "phase points",
                                            m, to_string(kind), x.size()));
  }
  return raw_variance(x, e, m);
}

double theo_br_bias(std::span<const double> x) {
  const std::size_t n = x.size();
  if (n < 24) throw core::InputError("data", "TheoBR needs at least 24 phase points");
  const auto count = static_cast<std::size_t>(std::floor(static_cast<double>(n) / 6.0 - 3.0));
  double sum = 0.0;
  for (std::size_t i = 0; i <= count; ++i) {
    sum += allan_variance_from_phase(x, 9 + 3 * i, AllanKind::kAllan) / theo1var(x, 12 + 4 * i);
  }
  return sum / static_cast<double>(count + 1);
}

double total_bias_factor(TotalKind kind, int alpha, std::size_t m, std::size_t phase_points) {
  const double md = static_cast<double>(m);
  const double n = static_cast<double>(phase_points);
  switch (kind) {
    case TotalKind::kTotal: {
      const double a = totvar_bias_a(alpha);
      return a == 0.0 ? 1.0 : 1.0 / (1.0 - a * md / n);
    }
    case TotalKind::kHadamardTotal:
      return m == 1 ? 1.0 : 1.0 / (1.0 + htotvar_bias_a(alpha));
    case TotalKind::kTheo1: {
      const Theo1Bias c = theo1_bias_coefficients(alpha);
      return c.a + c.b / std::pow(0.75 * md, c.c);
    }
    case TotalKind::kModifiedTotal:
    case TotalKind::kTimeTotal:
      return 1.0 / mtotvar_bias_ratio(alpha);
    default:
      return 1.0;
  }
}

int theo_br_noise_type(double bias) {
  // Nominal AVAR/Theo1 ratios of the power laws (Howe and Peppler 2003, as Stable32 names the
  // noise of a TheoBR run); the boundaries are the geometric means of neighbours.
  constexpr std::array<std::pair<int, double>, 5> kNominal{
      {{2, 0.4}, {1, 0.6}, {0, 1.0}, {-1, 1.71}, {-2, 2.24}}};
  for (std::size_t i = 0; i + 1 < kNominal.size(); ++i) {
    if (bias < std::sqrt(kNominal[i].second * kNominal[i + 1].second)) return kNominal[i].first;
  }
  return kNominal.back().first;
}

double total_equivalent_dof(TotalKind kind, int alpha, std::size_t m, std::size_t phase_points) {
  const double n = static_cast<double>(phase_points);
  const double md = static_cast<double>(m);
  const std::size_t samples = phase_points - 1;
  double b = 0.0, c = 0.0;
  double edf = kNaN;
  switch (kind) {
    case TotalKind::kTotal:
      edf = totvar_edf_coefficients(alpha, b, c)
                ? b * n / md - c
                : equivalent_dof(AllanKind::kAllan, alpha, m, samples);
      break;
    case TotalKind::kModifiedTotal:
    case TotalKind::kTimeTotal:
      // Stable32 gives the modified Allan variance's EDF below m = 16 (its MTOTDEV intervals
      // of PHASE.DAT at m = 1 to 8 are MDEV's to four digits): the fitted form is for long taus.
      edf = m >= 16 && mtotvar_edf_coefficients(alpha, b, c)
                ? b * n / md - c
                : equivalent_dof(AllanKind::kModified, alpha, m, samples);
      break;
    case TotalKind::kHadamardTotal:
      // Below m = 16 the Hadamard total is close to the overlapping Hadamard variance, and the
      // fitted form of the PTTI 2000 paper was made for longer taus.
      if (m >= 16 && htotvar_edf_coefficients(alpha, b, c)) {
        edf = (n / md) / (b + c * md / n);
      } else {
        edf = equivalent_dof(AllanKind::kHadamard, std::clamp(alpha, -4, 2), m, samples);
      }
      break;
    case TotalKind::kTheo1:
    case TotalKind::kTheoBr:
    case TotalKind::kTheoH:
      edf = theo1_edf(std::clamp(alpha, -2, 2), n, 0.75 * md);
      break;
  }
  return std::max(1.0, edf);
}

TotalResult total_deviation(std::span<const double> rate, double sample_rate_hz,
                            const TotalOptions& options) {
  options.validate();
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    throw core::InputError("rate",
                           fmt::format("must be positive and finite, got {}", sample_rate_hz));
  }
  const bool whole_record = options.kind == TotalKind::kTheoBr || options.kind == TotalKind::kTheoH;
  const std::size_t min_samples = whole_record ? 24 : 8;
  if (rate.size() < min_samples) {
    throw core::InputError("data", fmt::format("{} needs at least {} samples, got {}",
                                               to_string(options.kind), min_samples, rate.size()));
  }
  const std::vector<double> x = phase_from_rate(rate);
  const std::size_t n = x.size();
  const std::vector<Plan> plan = plan_points(options, n, sample_rate_hz);

  TotalResult out;
  out.kind = options.kind;
  out.sample_rate_hz = sample_rate_hz;
  out.samples = rate.size();
  out.confidence = options.confidence;
  out.bias_corrected = options.bias_correction;
  const double br = whole_record ? theo_br_bias(x) : 1.0;
  std::optional<int> last_alpha;
  for (const Plan& p : plan) {
    AllanPoint pt;
    pt.m = p.m;
    const bool theo = p.estimator == Estimator::kTheo1 || p.estimator == Estimator::kTheoBr;
    const double tau_samples = theo ? 0.75 * static_cast<double>(p.m) : static_cast<double>(p.m);
    pt.tau_s = tau_samples / sample_rate_hz;
    pt.terms = term_count(p.estimator, n, p.m);
    // The noise type: given, or identified here, or (too few decimated points) the last one
    // identified at a shorter tau, white FM if none was.
    int alpha = 0;
    if (options.alpha) {
      alpha = *options.alpha;
    } else {
      // TheoBR too: Stable32 names one noise type for a TheoBR run from its bias factor
      // (theo_br_noise_type()), but that factor averages AVAR/Theo1 out to N/2, where both are
      // noisy: PHASE.DAT, white FM, gets 0.60 ("flicker PM"), whose EDF would make the
      // intervals several times too narrow. The noise at each tau decides, as elsewhere.
      const std::optional<int> id = identify(x, p.estimator, p.m);
      if (id) last_alpha = id;
      alpha = last_alpha.value_or(0);
    }
    const int lo_alpha = p.estimator == Estimator::kHadamardTotal ? -4 : -2;
    alpha = std::clamp(alpha, lo_alpha, 2);
    pt.alpha = alpha;

    double var = raw_variance(x, p.estimator, p.m);
    if (p.estimator == Estimator::kTheoBr) {
      var *= br;
    } else if (options.bias_correction && p.estimator != Estimator::kAllan &&
               p.estimator != Estimator::kModifiedTotal) {
      var *= total_bias_factor(options.kind, alpha, p.m, n);
    }
    double dev = std::sqrt(var);
    if (options.kind == TotalKind::kTimeTotal) dev *= pt.tau_s / std::sqrt(3.0);
    pt.deviation = dev;

    if (options.intervals) {
      if (p.estimator == Estimator::kAllan) {
        pt.edf = equivalent_dof(AllanKind::kAllan, alpha, p.m, n - 1);
      } else {
        const TotalKind k = options.kind == TotalKind::kTheoH ? TotalKind::kTheoBr : options.kind;
        pt.edf = total_equivalent_dof(k, alpha, p.m, n);
      }
      const DeviationInterval ci = deviation_interval(dev, pt.edf, options.confidence);
      pt.lo = ci.lo;
      pt.hi = ci.hi;
    } else {
      pt.edf = pt.lo = pt.hi = kNaN;
    }
    out.points.push_back(pt);
  }
  return out;
}

}  // namespace calstand::solver

// The -3 dB bandwidth, low-pass order and delay of one gain/phase curve, and their intervals by
// a parametric bootstrap over the points' uncertainties.
#include "bandwidth_curve.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <random>

namespace calstand::analysis::detail {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kHalfPowerDb = -3.0102999566398120;  // 10 log10(1/2)
constexpr std::array kLowPassOrders{1, 2, 4, 6, 8};

double gain_db(double gain) { return 20.0 * std::log10(gain); }

// Phase [rad] of an analogue Butterworth low-pass of `order` at f / fc = x: its poles lie on the
// unit circle of the left half plane, and the phase is minus the sum of their angles seen from
// i x. Order 1 is the first-order lag, -atan(x).
double butterworth_phase(int order, double x) {
  double phase = 0.0;
  for (int k = 1; k <= order; ++k) {
    const std::complex<double> pole =
        std::polar(1.0, kPi * (2.0 * k + order - 1.0) / (2.0 * order));
    phase -= std::arg(std::complex<double>(0.0, x) - pole);
  }
  return phase;
}

double butterworth_gain_db(int order, double x) {
  return -10.0 * std::log10(1.0 + std::pow(x, 2.0 * order));
}

// The -3 dB crossing, interpolated linearly in dB over log frequency between the first two
// neighbours that straddle it.
std::optional<double> half_power(const std::vector<CurvePoint>& curve) {
  for (std::size_t k = 1; k < curve.size(); ++k) {
    const double g0 = gain_db(curve[k - 1].gain), g1 = gain_db(curve[k].gain);
    if (g0 >= kHalfPowerDb && g1 < kHalfPowerDb) {
      const double l0 = std::log(curve[k - 1].frequency_hz);
      const double l1 = std::log(curve[k].frequency_hz);
      return std::exp(l0 + (kHalfPowerDb - g0) / (g1 - g0) * (l1 - l0));
    }
  }
  return std::nullopt;
}

// The central `confidence` of `values` (sorted in place) and their standard deviation.
FigureInterval central(std::vector<double>& values, double confidence) {
  std::sort(values.begin(), values.end());
  const auto at = [&](double q) {
    const double pos = q * static_cast<double>(values.size() - 1);
    const auto i = static_cast<std::size_t>(std::floor(pos));
    const std::size_t j = std::min(i + 1, values.size() - 1);
    return values[i] + (pos - static_cast<double>(i)) * (values[j] - values[i]);
  };
  FigureInterval out;
  out.lo = at((1.0 - confidence) / 2.0);
  out.hi = at((1.0 + confidence) / 2.0);
  // Of the finite draws: a lost figure is kept as infinite only so that the quantiles count it.
  double mean = 0.0, count = 0.0;
  for (const double v : values) {
    if (std::isfinite(v)) mean += v, count += 1.0;
  }
  mean /= std::max(count, 1.0);
  double ss = 0.0;
  for (const double v : values) {
    if (std::isfinite(v)) ss += (v - mean) * (v - mean);
  }
  out.sigma = count > 1.0 ? std::sqrt(ss / (count - 1.0)) : 0.0;
  return out;
}

}  // namespace

CurveFigures read_curve(const std::vector<CurvePoint>& curve, int fixed_order) {
  CurveFigures out;
  out.bandwidth_hz = half_power(curve);
  const auto& fc = out.bandwidth_hz;
  if (fc && fixed_order > 0) {
    out.low_pass_order = fixed_order;
  } else if (fc) {
    double best = std::numeric_limits<double>::infinity();
    for (const int n : kLowPassOrders) {
      double cost = 0.0;
      for (const CurvePoint& p : curve) {
        const double r = gain_db(p.gain) - butterworth_gain_db(n, p.frequency_hz / *fc);
        cost += r * r;
      }
      if (cost < best) best = cost, out.low_pass_order = n;
    }
  }
  if (curve.size() < 2) return out;
  // What the low-pass model does not explain of the phase is the delay: -w tau, by least
  // squares through the origin.
  double num = 0.0, den = 0.0;
  for (const CurvePoint& p : curve) {
    const double omega = 2.0 * kPi * p.frequency_hz;
    const double model =
        out.low_pass_order > 0 ? butterworth_phase(out.low_pass_order, p.frequency_hz / *fc) : 0.0;
    num += (p.phase_rad - model) * omega;
    den += omega * omega;
  }
  out.delay_s = -num / den;
  return out;
}

CurveIntervals bootstrap_curve(const std::vector<CurvePoint>& curve, double confidence, int draws,
                               std::uint64_t seed) {
  CurveIntervals out;
  const CurveFigures data = read_curve(curve);
  const bool sigmas = std::all_of(curve.begin(), curve.end(), [](const CurvePoint& p) {
    return p.gain_sigma > 0.0 && p.phase_sigma_rad > 0.0 && p.sigma_dof > 0.0;
  });
  if (!sigmas || draws < 2) return out;
  // One engine for the whole curve, seeded per axis by the caller: the same run always gives
  // the same intervals.
  std::mt19937_64 engine(seed);
  std::vector<std::student_t_distribution<double>> t;
  for (const CurvePoint& p : curve) t.emplace_back(p.sigma_dof);
  std::vector<double> bandwidths, delays;
  std::vector<CurvePoint> moved = curve;
  for (int d = 0; d < draws; ++d) {
    for (std::size_t k = 0; k < curve.size(); ++k) {
      moved[k].gain = curve[k].gain + curve[k].gain_sigma * t[k](engine);
      moved[k].phase_rad = curve[k].phase_rad + curve[k].phase_sigma_rad * t[k](engine);
      moved[k].gain = std::max(moved[k].gain, std::numeric_limits<double>::min());
    }
    const CurveFigures f = read_curve(moved, data.low_pass_order);
    // A draw whose gains no longer cross -3 dB has it beyond the frequencies tested (they
    // fall with frequency): infinite, so that it counts in the upper tail, and with no delay,
    // which is read after the low-pass phase at the draw's own bandwidth.
    if (data.bandwidth_hz) bandwidths.push_back(f.bandwidth_hz.value_or(INFINITY));
    const bool comparable = f.bandwidth_hz.has_value() == data.bandwidth_hz.has_value();
    if (data.delay_s && f.delay_s) delays.push_back(comparable ? *f.delay_s : INFINITY);
  }
  if (data.bandwidth_hz) {
    const FigureInterval i = central(bandwidths, confidence);
    if (std::isfinite(i.hi)) out.bandwidth_hz = i;
  }
  if (data.delay_s) {
    // A lost bandwidth leaves the delay undetermined in either direction: the interval holds
    // only when such draws fit in one tail.
    const FigureInterval i = central(delays, confidence);
    if (std::isfinite(i.hi)) out.delay_s = i;
  }
  return out;
}

}  // namespace calstand::analysis::detail

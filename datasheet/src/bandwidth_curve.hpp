#pragma once
// One axis's gain and phase curve read as datasheet figures (the -3 dB bandwidth, the low-pass
// order, the pure delay), and the 95 % intervals of those figures from the points' own
// uncertainties. Internal to analysis/: bandwidth.cpp reads the steps, this reads the curve.

#include <cstdint>
#include <optional>
#include <vector>

namespace calstand::analysis::detail {

/// One frequency of an axis's curve, with its one-sigma uncertainties (0: unknown).
struct CurvePoint {
  double frequency_hz = 0.0;
  double gain = 0.0;        ///< ratio, not dB
  double phase_rad = 0.0;   ///< unwrapped along frequency
  double gain_sigma = 0.0;  ///< [ratio]
  double phase_sigma_rad = 0.0;
  /// Degrees of freedom of both sigmas (segments - 1); the bootstrap draws Student-t with them.
  double sigma_dof = 0.0;
};

/// The figures of one curve, as analyse_bandwidth() reports them.
struct CurveFigures {
  std::optional<double> bandwidth_hz;  ///< -3 dB, interpolated in dB over log frequency
  int low_pass_order = 0;              ///< Butterworth order whose gains fit best; 0 without fc
  std::optional<double> delay_s;       ///< phase slope after the low-pass model's phase
};

/// The figures of `curve` (by increasing frequency). The order is chosen unless `fixed_order`
/// (> 0) is given.
CurveFigures read_curve(const std::vector<CurvePoint>& curve, int fixed_order = 0);

/// A two-sided interval and the standard deviation of the draws it came from.
struct FigureInterval {
  double lo = 0.0;
  double hi = 0.0;
  double sigma = 0.0;
};

struct CurveIntervals {
  std::optional<FigureInterval> bandwidth_hz;
  std::optional<FigureInterval> delay_s;
};

/// Parametric bootstrap of read_curve() over the points' uncertainties: `draws` curves, each
/// point's gain and phase moved by its sigma times a Student-t draw with its degrees of freedom
/// (the sigmas are themselves estimates), the low-pass order held at the one read from the
/// data; the interval holds the central `confidence` of the draws' figures. None for a figure
/// the data lack, a point without a sigma, or when more than (1 - confidence) / 2 of the draws
/// lose the figure (the -3 dB crossing leaves the frequencies tested). Deterministic for a
/// `seed`.
CurveIntervals bootstrap_curve(const std::vector<CurvePoint>& curve, double confidence, int draws,
                               std::uint64_t seed);

}  // namespace calstand::analysis::detail

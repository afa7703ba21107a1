#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <span>

namespace calstand::solver {

/// Dominant power-law noise of a record at one averaging factor by the lag-1 autocorrelation
/// (W. Riley and C. Greenhall, "Power law noise identification using the lag 1
/// autocorrelation", 18th EFTF, 2004; NIST SP 1065 section 5.5.5).
struct Lag1NoiseId {
  double alpha_estimate = 0.0;  ///< the unrounded exponent p + 2 (S_y ~ f^alpha)
  int alpha = 0;                ///< rounded, clamped to the estimator's range
  int differences = 0;          ///< differences taken before the autocorrelation fell below 0.25
  std::size_t points = 0;       ///< decimated phase points the autocorrelation was taken on
};

/// Minimum decimated points for the method: the paper finds it reliable from about 30.
inline constexpr std::size_t kLag1MinPoints = 30;

/// The noise type at averaging factor m of the phase `x` (N points, any unit): the phase is
/// decimated by m (every m-th point), then differenced d = 0, 1, ... times until
/// delta = r1 / (1 + r1) of the lag-1 autocorrelation r1 is below 0.25 or d = dmax
/// (2 for the Allan family, 3 for the Hadamard family); p = -2 (delta + d) is the phase
/// spectrum's exponent and alpha = p + 2. The result is rounded and clamped to
/// [min_alpha, 2]. nullopt when fewer than kLag1MinPoints decimated points remain (the
/// caller carries a type identified at a shorter tau forward) or the data are constant.
/// The autocorrelation is taken about the series' mean; nothing else is removed (no trend),
/// so a linear ramp in `x` changes the answer at d = 0.
std::optional<Lag1NoiseId> identify_noise_lag1(std::span<const double> x, std::size_t m, int dmax,
                                               int min_alpha);

/// The largest power of two m at which identify_noise_lag1() still has kLag1MinPoints decimated
/// points of a phase of samples + 1 points (floor(samples / m) + 1 of them); 0 when even m = 1
/// has too few. The Allan kinds carry the type identified there to the taus beyond, whatever
/// the tau set (see allan()): it is on the octave grid, which a streamed record also has.
std::size_t lag1_longest_octave_factor(std::size_t samples);

/// identify_noise_lag1() of a phase that streams past: the decimated phase points z_0, z_1, ...
/// (every m-th point, m fixed by the caller) are pushed one, or a strided run, at a time, and
/// for each difference order d = 0 .. dmax of them only what the lag-1 autocorrelation about
/// the mean needs is kept: the count, the sum, the sum of squares, the sum of neighbour
/// products, the first and the last value; for d = 0 also sum k z_k, to take out a linear ramp
/// afterwards. Memory does not grow with the record. solver::DeviationStream keeps one per octave
/// averaging factor.
class Lag1Accumulator {
 public:
  /// Differences to accumulate: at most kMaxDifferences.
  static constexpr int kMaxDifferences = 3;
  explicit Lag1Accumulator(int dmax);

  /// Appends the next decimated phase point.
  void push(double z);
  /// Appends z[0] + offset, z[stride] + offset, ... (n points): the same sums, bit for bit, as
  /// pushing them one at a time, in a loop without branches once every order has begun.
  void push(const double* z, std::size_t n, std::size_t stride, double offset);
  /// Decimated points pushed.
  std::size_t points() const { return points_; }

  /// What identify_noise_lag1(x, m, dmax, min_alpha) gives when the points pushed are
  /// z_k = x[k m] + ramp * k: the ramp is taken out of the d = 0 sums algebraically (the
  /// differenced series only shift by it, which the autocorrelation about the mean ignores).
  /// `dmax` is at most the constructor's. Equal to the in-memory answer up to rounding: the sums
  /// are taken in one pass, and taking the ramp out of them cancels, by about 1e-16 times
  /// (ramp * points / the spread of the ramp-free series)^2 and growing with the points: 1.5e-9
  /// in alpha for a ramp a thousand times the spread over 20,001 points.
  std::optional<Lag1NoiseId> identify(int dmax, int min_alpha, double ramp = 0.0) const;

 private:
  // One difference order's series y_0, y_1, ...: the sums in two lanes, of the points of even
  // and of odd index (k of z_k), so that pairs of points are summed in one instruction and the
  // sums do not depend on how the points were split into calls.
  struct Sums {
    double n = 0.0, first = 0.0, last = 0.0;
    std::array<double, 2> sum{}, squares{}, products{};
  };
  template <int D>
  void push_each(const double* z, std::size_t n, std::size_t stride, double offset);

  int dmax_;
  std::size_t points_ = 0;
  std::array<Sums, kMaxDifferences + 1> sums_{};
  std::array<double, 2> weighted_{};  // sum over k of k z_k (d = 0), by lane
};

}  // namespace calstand::solver

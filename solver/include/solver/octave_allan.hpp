#pragma once
// The Allan variance inside a step at octave block lengths (1, 2, 4, ... samples), and the
// white noise that the pooled curve shows once the slower processes are taken out of it.
//
// Why a curve and not one block length: a step's scatter at any single block length mixes the
// white noise with the bias wander at that time scale. On an ADIS16488-class accelerometer the
// flicker floor (0.1 mg) is 15 times the white noise of a 6 s block, so a floor taken at a tenth
// of a 60 s step was 28 times the true white variance; the step means were then weighted as if
// their scatter fell as 1/n, and the wander kernels saw only what the floor had left. The
// curve separates the two the way IEEE Std 952-1997 Annex C reads an Allan plot: white noise
// falls as 1/tau, flicker is flat, a random walk or a drift rises; the white part is the 1/tau
// term of a fit of those slopes.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "solver/model.hpp"

namespace calstand::solver {

using Vector6d = Eigen::Matrix<double, kChannels, 1>;

/// The Allan variance sums of one octave: half the squared differences of neighbouring
/// non-overlapping block means of 2^octave samples, per channel, and how many differences.
struct OctaveAllan {
  Vector6d half_squared_differences = Vector6d::Zero();  ///< [unit^2]
  std::int64_t differences = 0;
};

/// Block lengths below this many samples are left out of the white fit: an output filter
/// correlates neighbouring samples, which lowers the Allan variance at the shortest blocks.
inline constexpr int kWhiteFitShortestBlockSamples = 4;

/// Streams one step's values (measurement - reference, per channel) into the Allan sums of
/// `octaves` octaves, block lengths 1 to 2^(octaves - 1) samples, in one pass and O(octaves)
/// memory: each finished block is passed to the next octave as half of its block.
class OctaveAllanSums {
 public:
  explicit OctaveAllanSums(int octaves);
  void add(const Vector6d& value) { push(0, value); }
  /// The sums, one per octave, shortest block first.
  std::vector<OctaveAllan> result() const;

 private:
  struct Octave {
    Vector6d previous = Vector6d::Zero();    ///< the last finished block's mean
    Vector6d first_half = Vector6d::Zero();  ///< the pending block of the next octave
    bool has_previous = false;
    bool has_first_half = false;
    OctaveAllan sums;
  };
  void push(std::size_t octave, const Vector6d& block_mean);
  std::vector<Octave> octaves_;
};

/// The octaves a step of `samples` samples reports: blocks up to a tenth of the step, so that
/// each octave has at least nine differences.
int octaves_for(std::int64_t samples);

/// The white variance of one sample per channel from octave sums pooled over steps:
/// a weighted least-squares fit of tau times the Allan variance, m AVAR(m) = q + d / m + c1 m +
/// c2 m^2 (white q; d <= 0: an output filter's deficit at short blocks; c1 >= 0: flicker;
/// c2 >= 0: a random walk, a Gauss-Markov bias at times below its correlation time, or a
/// drift), over block lengths from kWhiteFitShortestBlockSamples to `longest_block_samples`.
/// std::nullopt when fewer than three octaves are usable.
std::optional<Vector6d> white_variance_from_octaves(const std::vector<OctaveAllan>& pooled,
                                                    std::int64_t longest_block_samples);

}  // namespace calstand::solver

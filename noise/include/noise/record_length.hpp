#pragma once
// How long a static record must be for each noise figure (issue 32): `calstand noise` says what
// the record gives against what each figure needs ("bias instability needs about 3 h; this
// record has 41 min").

#include <string>
#include <vector>

#include "noise/run_noise.hpp"

namespace calstand::solver {

/// The rule: a figure read off the Allan curve at averaging time tau is known when the 95 %
/// confidence interval of the deviation there is within +-25 % of it; the record is long enough
/// when the equivalent degrees of freedom of the overlapping Allan variance at that tau
/// (equivalent_dof(), Greenhall and Riley; the noise type the figure is) reach the edf that
/// interval needs (47.8: deviation_interval(1, edf, 0.95) within [0.75, 1.25], the upper end
/// binding).
struct RecordLengthRule {
  double confidence = 0.95;      ///< two-sided probability of the interval
  double half_width = 0.25;      ///< relative half width of the interval of the deviation
  double rrw_tau_factor = 4.0;   ///< rate random walk read this many times the minimum's tau
  double min_points_edf = 10.0;  ///< as NoiseTerms: points with fewer edf do not place the minimum
};

/// The record a noise figure needs.
struct FigureRecordNeed {
  std::string figure;  ///< "random_walk", "bias_instability" or "rate_random_walk"
  bool gyro = true;
  std::string channel;           ///< the axis (gx ... az) that needs the longest record
  double tau_s = 0.0;            ///< where the figure is read [s]
  int alpha = 0;                 ///< the noise type there (0 white FM, -1 flicker FM, -2 RW FM)
  double needed_s = 0.0;         ///< record length that gives the interval [s]
  double record_length_s = 0.0;  ///< the record's length [s]
  bool enough = false;           ///< record_length_s >= needed_s
  /// False when the figure's tau is not located by this record (the Allan minimum at the
  /// longest well-determined tau: the curve still falls); needed_s is then a lower bound.
  bool located = true;
};

/// The edf the rule's interval needs.
double required_edf(const RecordLengthRule& rule = {});

/// The shortest record [s] at `sample_rate_hz` whose overlapping Allan variance at `tau_s` has
/// `edf` equivalent degrees of freedom for noise type `alpha`.
double record_length_for_edf(double tau_s, int alpha, double sample_rate_hz, double edf);

/// Per sensor (gyro, accelerometer) and figure (random walk N at tau 1 s with white FM; bias
/// instability at the tau of the Allan minimum with flicker FM; rate random walk at
/// rrw_tau_factor times that tau with random-walk FM), the axis that needs the longest record,
/// against the record of `noise`.
std::vector<FigureRecordNeed> record_length_needs(const RunNoise& noise,
                                                  const RecordLengthRule& rule = {});

/// "41 min", "3.0 h", "12 s", "2.1 d".
std::string format_record_length(double seconds);

}  // namespace calstand::solver

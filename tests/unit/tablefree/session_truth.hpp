#pragma once
// Simulated sessions (sim/hand_session.hpp) for the tests, the truth a calibration of one
// should find, by contract parameter name, and pulls of estimates against it.

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/hand_session.hpp"
#include "tablefree/triad_model.hpp"

namespace calstand::solver::testing {

/// A hand-held session of `spec` at a decimated 200 Hz output with a 30 s initial rest and
/// `poses` spread poses: what the detector and gravity-norm tests calibrate.
inline sim::SimSession hand_session_200hz(const char* spec, std::uint64_t seed, int poses = 20) {
  sim::HandSessionOptions o;
  o.imu.spec = spec;
  o.imu.sample_rate_hz = 200.0;
  o.poses = poses;
  o.initial_rest_s = 30.0;
  return sim::simulate_hand_session(o, seed);
}

/// The truth of `name` in frame A for this session: the fixed value, plus for biases what the
/// session itself adds to them: the slow noise averaged over the holds (accel; gyro in a
/// Ferraris session), or over the initial rest together with the Earth rate there (gyro of a
/// hand session, whose bias comes from the rest; `earth_rate_modelled`: a fit that models the
/// Earth rate takes it out of the rest mean, leaving the slow noise only).
inline double session_truth(const sim::SimSession& s, const std::string& name,
                            bool earth_rate_modelled = false) {
  double t = 0.0;
  for (const auto& [n, v] : s.truth.parameters()) {
    if (n == name) t = v;
  }
  const auto axis = static_cast<std::size_t>(name.back() - 'x');
  if (name.rfind("accel_bias.", 0) == 0) t += s.slow_noise_mean_holds[3 + axis];
  if (name.rfind("gyro_bias.", 0) == 0) {
    if (s.kind == "hand") {
      t += s.slow_noise_mean_rest[axis];
      if (!earth_rate_modelled) t += s.rest_true_rate_A_dps[static_cast<Eigen::Index>(axis)];
    } else {
      t += s.slow_noise_mean_holds[axis];
    }
  }
  return t;
}

struct Pull {
  std::string name;
  double pull;
};

/// (estimate - truth) / sigma of every estimated parameter with a sigma.
inline std::vector<Pull> session_pulls(const sim::SimSession& s,
                                       const std::vector<TriadEstimate>& estimates,
                                       bool earth_rate_modelled = false) {
  std::vector<Pull> out;
  for (const TriadEstimate& e : estimates) {
    if (e.status != EstimateStatus::kEstimated || !(e.sigma > 0.0)) continue;
    out.push_back({e.name, (e.value - session_truth(s, e.name, earth_rate_modelled)) / e.sigma});
  }
  return out;
}

inline double rms_pull(const std::vector<Pull>& pulls) {
  double sum = 0.0;
  for (const Pull& p : pulls) sum += p.pull * p.pull;
  return pulls.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(pulls.size()));
}

}  // namespace calstand::solver::testing

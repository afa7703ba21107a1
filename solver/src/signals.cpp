#include "solver/signals.hpp"

#include <cmath>

#include "core/rotation.hpp"

namespace calstand::solver {

const std::vector<std::string_view>& signal_names() {
  static const std::vector<std::string_view> kNames{
      "temperature", "temperature_rate", "elapsed", "rate_x",       "rate_y",       "rate_z",
      "force_x",     "force_y",          "force_z", "table_rate_x", "table_rate_y", "table_rate_z"};
  return kNames;
}

std::array<double, kSignalCount> signal_values(const Signals& s) {
  return {s.temperature_c,  s.temperature_rate_cpm, s.elapsed_s,          s.rate_dps.x(),
          s.rate_dps.y(),   s.rate_dps.z(),         s.force_mps2.x(),     s.force_mps2.y(),
          s.force_mps2.z(), s.table_rate_dps.x(),   s.table_rate_dps.y(), s.table_rate_dps.z()};
}

SignalBuilder::SignalBuilder(const RunSetup& setup, bool with_earth_rate)
    : geometry_(setup.geometry),
      force_level_mps2_(setup.site.specific_force_level()),
      earth_level_dps_(setup.site.earth_rate_level_radps() * core::kRadToDeg),
      temperature_ref_c_(setup.temperature_ref_c),
      with_earth_rate_(with_earth_rate),
      outer_unit_(setup.geometry.outer_axis.normalized()),
      outer_unit_renormalises_(outer_unit_.normalized() != outer_unit_) {}

Signals SignalBuilder::operator()(const core::ImuSample& sample, const store::TableSample& table,
                                  double temperature_rate_cpm, double elapsed_s) const {
  Signals s = with_inputs(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), table,
                          sample.temperature_c, temperature_rate_cpm, elapsed_s);
  s.rate_dps =
      with_earth_rate_ ? Eigen::Vector3d(s.table_rate_dps + s.earth_rate_dps) : s.table_rate_dps;
  s.force_mps2 = s.C_BL * force_level_mps2_;
  return s;
}

void SignalBuilder::advance_at_same_table(Signals& signals, const core::ImuSample& sample,
                                          double temperature_rate_cpm, double elapsed_s) const {
  signals.temperature_c = sample.temperature_c;
  signals.dT_c = sample.temperature_c - temperature_ref_c_;
  signals.temperature_rate_cpm = temperature_rate_cpm;
  signals.elapsed_s = elapsed_s;
}

Signals SignalBuilder::with_inputs(const Eigen::Vector3d& rate_dps,
                                   const Eigen::Vector3d& force_mps2,
                                   const store::TableSample& table, double temperature_c,
                                   double temperature_rate_cpm, double elapsed_s) const {
  Signals s;
  s.temperature_c = temperature_c;
  s.dT_c = temperature_c - temperature_ref_c_;
  s.temperature_rate_cpm = temperature_rate_cpm;
  s.elapsed_s = elapsed_s;
  // TableGeometry's body_to_level(), table_rate_level_dps() and table_accel_level_dps2() (no
  // axis acceleration) with the outer axis' rotation computed once instead of three times:
  // the same arithmetic, for the trigonometry that took a fifth of a long run's summaries.
  const double outer_rad = table.outer_deg * core::kDegToRad;
  const Eigen::Matrix3d outer_turn = core::axis_angle(geometry_.outer_axis, outer_rad);
  const Eigen::Matrix3d C_LB =
      outer_turn * core::axis_angle(geometry_.inner_axis, table.inner_deg * core::kDegToRad) *
      geometry_.mount_C_PB;
  s.C_BL = C_LB.transpose();
  const Eigen::Vector3d inner_now = outer_turn * geometry_.inner_axis.normalized();
  const Eigen::Vector3d rate_level_dps =
      table.outer_rate_dps * outer_unit_ + table.inner_rate_dps * inner_now;
  s.table_rate_dps = s.C_BL * rate_level_dps;
  const Eigen::Vector3d inner_now_accel =
      outer_unit_renormalises_ ? Eigen::Vector3d(core::axis_angle(outer_unit_, outer_rad) *
                                                 geometry_.inner_axis.normalized())
                               : inner_now;
  constexpr double kAxisAccelDps2 = 0.0;  // the axes turn at constant rates within a step
  const Eigen::Vector3d carried =
      (table.outer_rate_dps * core::kDegToRad * outer_unit_).cross(inner_now_accel);
  const Eigen::Vector3d accel_level_dps2 = kAxisAccelDps2 * outer_unit_ +
                                           kAxisAccelDps2 * inner_now_accel +
                                           table.inner_rate_dps * carried;
  s.table_accel_dps2 = s.C_BL * accel_level_dps2;
  s.earth_rate_dps = s.C_BL * earth_level_dps_;
  s.rate_dps = rate_dps;
  s.force_mps2 = force_mps2;
  return s;
}

std::vector<double> step_temperature_rates(const std::vector<core::ImuSample>& samples,
                                           double half_window_s) {
  const std::size_t n = samples.size();
  std::vector<double> rates(n, 0.0);
  if (n < 2) return rates;
  // Prefix sums of t, T, t^2 and tT (t relative to the first sample for conditioning) give each
  // window's slope in O(1).
  const double t0 = samples.front().receive_time_s;
  const double T0 = samples.front().temperature_c;
  std::vector<double> st(n + 1, 0.0), sT(n + 1, 0.0), stt(n + 1, 0.0), stT(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = samples[i].receive_time_s - t0;
    const double T = samples[i].temperature_c - T0;
    st[i + 1] = st[i] + t;
    sT[i + 1] = sT[i] + T;
    stt[i + 1] = stt[i] + t * t;
    stT[i + 1] = stT[i] + t * T;
  }
  std::size_t lo = 0;
  std::size_t hi = 0;  // window [lo, hi)
  for (std::size_t i = 0; i < n; ++i) {
    const double t = samples[i].receive_time_s;
    while (samples[lo].receive_time_s < t - half_window_s) ++lo;
    while (hi < n && samples[hi].receive_time_s <= t + half_window_s) ++hi;
    const double m = static_cast<double>(hi - lo);
    const double sx = st[hi] - st[lo];
    const double sy = sT[hi] - sT[lo];
    const double sxx = stt[hi] - stt[lo];
    const double sxy = stT[hi] - stT[lo];
    const double den = m * sxx - sx * sx;
    rates[i] = m >= 2.0 && den > 0.0 ? (m * sxy - sx * sy) / den * 60.0 : 0.0;
  }
  return rates;
}

}  // namespace calstand::solver

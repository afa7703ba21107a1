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
      with_earth_rate_(with_earth_rate) {}

Signals SignalBuilder::operator()(const core::ImuSample& sample, const store::TableSample& table,
                                  double temperature_rate_cpm, double elapsed_s) const {
  Signals s = with_inputs(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), table,
                          sample.temperature_c, temperature_rate_cpm, elapsed_s);
  s.rate_dps =
      with_earth_rate_ ? Eigen::Vector3d(s.table_rate_dps + s.earth_rate_dps) : s.table_rate_dps;
  s.force_mps2 = s.C_BL * force_level_mps2_;
  return s;
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
  s.C_BL = geometry_.body_to_level(table.outer_deg, table.inner_deg).transpose();
  s.table_rate_dps = s.C_BL * geometry_.table_rate_level_dps(table.outer_deg, table.outer_rate_dps,
                                                             table.inner_rate_dps);
  s.table_accel_dps2 =
      s.C_BL * geometry_.table_accel_level_dps2(table.outer_deg, table.outer_rate_dps,
                                                table.inner_rate_dps, 0.0, 0.0);
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

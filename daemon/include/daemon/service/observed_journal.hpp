#pragma once

#include <Eigen/Core>
#include <chrono>
#include <cstdint>
#include <map>
#include <set>
#include <string>

#include "daemon/run_journal.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/live_status.hpp"

namespace calstand::daemon::service {

/// A RunJournal that records through `inner` (the store) and also tells live readers: step
/// changes, run state changes and events as they happen, and telemetry every
/// `telemetry_period` of wall time (publish_telemetry(), which the daemon calls from the
/// engine's progress callback: the journal's own telemetry comes once a station second, too
/// slowly in real time and far too fast on a simulated clock). Called on the engine thread
/// only, like any journal.
class ObservedJournal final : public RunJournal {
 public:
  ObservedJournal(RunJournal& inner, EventHub& hub, LiveStatus& live, std::int64_t run_id,
                  std::chrono::milliseconds telemetry_period = std::chrono::milliseconds(500));

  void step_started(std::size_t step, int attempt, double t_s) override;
  bool add_samples(std::size_t step, int attempt, const std::string& device,
                   const std::vector<core::ImuSample>& samples) override;
  void wait_for_writer() override { inner_.wait_for_writer(); }
  void discard_attempt(std::size_t step, int attempt, const std::string& why) override;
  void step_completed(std::size_t step, int attempt, double t_s) override;
  void step_failed(std::size_t step, int attempt, double t_s, const std::string& why) override;
  void step_skipped(std::size_t step, double t_s, const std::string& why) override;
  void event(double t_s, EventKind kind, const std::string& source,
             const std::string& message) override;
  void table_telemetry(const core::TableState& state) override;
  void table_trace(const core::TableState& state) override { inner_.table_trace(state); }
  void chamber_telemetry(const core::ChamberState& state) override;
  void run_state(RunState state, double t_s, const std::string& reason) override;
  std::string unit_identified(const std::string& imu, const std::string& model,
                              const std::string& serial) override {
    return inner_.unit_identified(imu, model, serial);
  }

  /// The station's device names: an event whose source is one of them is logged with the
  /// DEVICE field (log_fields.hpp).
  void set_devices(std::set<std::string> names) { devices_ = std::move(names); }

  /// True when the next telemetry message is due (wall time).
  bool telemetry_due() const { return std::chrono::steady_clock::now() >= next_telemetry_; }
  /// Publishes the station's state now as the live telemetry (and the latest in /station),
  /// with each IMU's samples since the last telemetry summed up (`imus`: count, station-time
  /// rate, channel means), so that a live plot needs no raw samples.
  void publish_telemetry(const core::TableState& table, const core::ChamberState& chamber);

 private:
  // One IMU's samples since the last telemetry message.
  struct ImuWindow {
    std::size_t count = 0;
    double first_receive_s = 0.0;
    double last_receive_s = 0.0;
    Eigen::Vector3d gyro_sum_dps = Eigen::Vector3d::Zero();
    Eigen::Vector3d accel_sum_mps2 = Eigen::Vector3d::Zero();
    double temperature_sum_c = 0.0;
  };

  void publish_step(std::size_t step, int attempt, double t_s, const char* status,
                    const std::string& why = "");

  RunJournal& inner_;
  EventHub& hub_;
  LiveStatus& live_;
  std::int64_t run_id_;
  std::chrono::milliseconds telemetry_period_;
  std::chrono::steady_clock::time_point next_telemetry_{};
  std::map<std::string, ImuWindow> imu_windows_;  // by device name
  std::set<std::string> devices_;
};

}  // namespace calstand::daemon::service

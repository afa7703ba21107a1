#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/chamber_state.hpp"
#include "core/imu_sample.hpp"
#include "core/table_state.hpp"
#include "daemon/run_state.hpp"

namespace calstand::daemon {

/// Where the engine records what happens during a run. The store implements it on SQLite
/// (StoreJournal); tests use an in-memory one. Times are station-clock seconds.
///
/// Contract the engine relies on for crash resume: after step_completed() returns, that step
/// and every sample of its final attempt are durable; samples of other attempts are discarded.
class RunJournal {
 public:
  virtual ~RunJournal() = default;
  virtual void step_started(std::size_t step, int attempt, double t_s) = 0;
  /// Queues the samples of one capture attempt of `device`; false when they could not be
  /// queued (writer overflow), which the engine records as a fault.
  virtual bool add_samples(std::size_t step, int attempt, const std::string& device,
                           const std::vector<core::ImuSample>& samples) = 0;
  /// Blocks until the sample writer has caught up with everything queued. A simulated station
  /// produces samples as fast as the CPU allows, so on a virtual clock the engine waits for the
  /// writer instead of overflowing it; on a real clock an overflow stays a recorded fault.
  virtual void wait_for_writer() {}
  /// Drops every sample of that attempt (an invalidated or interrupted capture).
  virtual void discard_attempt(std::size_t step, int attempt, const std::string& why) = 0;
  /// Makes the step and the samples of `attempt` durable, then returns.
  virtual void step_completed(std::size_t step, int attempt, double t_s) = 0;
  virtual void step_failed(std::size_t step, int attempt, double t_s, const std::string& why) = 0;
  /// The operator skipped the step (`why` says who and why); a resumed run does not redo it.
  /// Any capture attempt in progress was discarded before this.
  virtual void step_skipped(std::size_t step, double t_s, const std::string& why) = 0;
  virtual void event(double t_s, EventKind kind, const std::string& source,
                     const std::string& message) = 0;
  virtual void table_telemetry(const core::TableState& state) = 0;
  /// A table reading of an oscillation, every one kept (no decimation to the telemetry
  /// period): the bandwidth analysis fits the encoder's sine on them. Stored with the table
  /// telemetry; durable at the latest with the step. Default: as table_telemetry().
  virtual void table_trace(const core::TableState& state) { table_telemetry(state); }
  virtual void chamber_telemetry(const core::ChamberState& state) = 0;
  virtual void run_state(RunState state, double t_s, const std::string& reason) = 0;
  /// The unit in slot `imu` reported its identity when the station came up. Returns why the
  /// run must not go on (another unit than the run was given for sits in the slot), or empty
  /// when the identity is recorded.
  virtual std::string unit_identified(const std::string& imu, const std::string& model,
                                      const std::string& serial) = 0;
};

}  // namespace calstand::daemon

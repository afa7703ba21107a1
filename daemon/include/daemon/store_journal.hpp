#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <tuple>

#include "daemon/run_journal.hpp"
#include "store/capture_writer.hpp"
#include "store/run_store.hpp"

namespace calstand::daemon {

/// RunJournal on the SQLite store: steps, events, telemetry and run status through a RunStore
/// (the engine thread's connection), samples through a CaptureWriter (its own thread).
/// step_completed() returns only once CaptureWriter::commit_step() has made the step durable.
class StoreJournal final : public RunJournal {
 public:
  /// `store` and `writer` must outlive the journal; `run_id` exists with its steps added.
  /// `wait_when_busy`: before the writer's queue is half full, wait for it (for simulated
  /// stations, whose samples come as fast as the CPU allows); otherwise a full queue is an
  /// overflow fault, as it must be for real devices.
  StoreJournal(store::RunStore& store, store::CaptureWriter& writer, std::int64_t run_id,
               double telemetry_period_s = 0.1, bool wait_when_busy = false,
               std::size_t writer_queue_capacity = store::CaptureWriterOptions{}.queue_capacity);

  void step_started(std::size_t step, int attempt, double t_s) override;
  bool add_samples(std::size_t step, int attempt, const std::string& device,
                   const std::vector<core::ImuSample>& samples) override;
  void wait_for_writer() override { writer_.flush(); }
  void discard_attempt(std::size_t step, int attempt, const std::string& why) override;
  void step_completed(std::size_t step, int attempt, double t_s) override;
  void step_failed(std::size_t step, int attempt, double t_s, const std::string& why) override;
  void step_skipped(std::size_t step, double t_s, const std::string& why) override;
  void event(double t_s, EventKind kind, const std::string& source,
             const std::string& message) override;
  void table_telemetry(const core::TableState& state) override;
  void table_trace(const core::TableState& state) override;
  void chamber_telemetry(const core::ChamberState& state) override;
  void run_state(RunState state, double t_s, const std::string& reason) override;
  std::string unit_identified(const std::string& imu, const std::string& model,
                              const std::string& serial) override;

  std::int64_t run_id() const { return run_id_; }

 private:
  /// Writes the buffered trace rows in one transaction (a row per transaction would cost a
  /// commit per control tick).
  void flush_trace();
  std::vector<core::TableState> trace_;
  std::int64_t step_id(std::size_t step);

  store::RunStore& store_;
  store::CaptureWriter& writer_;
  std::int64_t run_id_;
  std::map<std::size_t, std::int64_t> step_ids_;
  std::map<std::tuple<std::int64_t, int, std::string>, store::CaptureWriter::StreamId> streams_;
  store::TelemetryDecimator table_decimator_;
  store::TelemetryDecimator chamber_decimator_;
  bool started_ = false;
  bool wait_when_busy_;
  std::size_t queue_capacity_;
};

}  // namespace calstand::daemon

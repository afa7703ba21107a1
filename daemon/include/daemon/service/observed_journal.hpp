#pragma once

#include <chrono>
#include <cstdint>

#include "daemon/run_journal.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/live_status.hpp"

namespace calstand::daemon::service {

/// A RunJournal that records through `inner` (the store) and also tells live readers: step
/// changes, run state changes and events as they happen, telemetry at most every
/// `telemetry_period` of wall time (a simulated station produces it far faster than anyone
/// reads). Called on the engine thread only, like any journal.
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
  void event(double t_s, EventKind kind, const std::string& source,
             const std::string& message) override;
  void table_telemetry(const core::TableState& state) override;
  void chamber_telemetry(const core::ChamberState& state) override;
  void run_state(RunState state, double t_s, const std::string& reason) override;

 private:
  void publish_step(std::size_t step, int attempt, double t_s, const char* status,
                    const std::string& why = "");
  void publish_telemetry_when_due();

  RunJournal& inner_;
  EventHub& hub_;
  LiveStatus& live_;
  std::int64_t run_id_;
  std::chrono::milliseconds telemetry_period_;
  std::chrono::steady_clock::time_point next_telemetry_{};
};

/// JSON of the table and chamber states as the API shows them (units in the keys).
nlohmann::json to_json(const core::TableState& table);
nlohmann::json to_json(const core::ChamberState& chamber);

}  // namespace calstand::daemon::service

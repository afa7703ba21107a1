#include "daemon/store_journal.hpp"

#include <fmt/format.h>

#include "store/units.hpp"

namespace calstand::daemon {
namespace {
constexpr std::size_t kTraceBatch = 256;  // rows per transaction [-]
}  // namespace

StoreJournal::StoreJournal(store::RunStore& store, store::CaptureWriter& writer,
                           std::int64_t run_id, double telemetry_period_s, bool wait_when_busy,
                           std::size_t writer_queue_capacity)
    : store_(store),
      writer_(writer),
      run_id_(run_id),
      table_decimator_(telemetry_period_s),
      chamber_decimator_(telemetry_period_s),
      wait_when_busy_(wait_when_busy),
      queue_capacity_(writer_queue_capacity) {}

std::int64_t StoreJournal::step_id(std::size_t step) {
  auto it = step_ids_.find(step);
  if (it == step_ids_.end()) it = step_ids_.emplace(step, store_.step_id(run_id_, step)).first;
  return it->second;
}

void StoreJournal::step_started(std::size_t step, int attempt, double t_s) {
  store_.mark_step_running(run_id_, step, attempt, store::Stamp::now(t_s));
}

bool StoreJournal::add_samples(std::size_t step, int attempt, const std::string& device,
                               const std::vector<core::ImuSample>& samples) {
  const std::int64_t id = step_id(step);
  const auto key = std::make_tuple(id, attempt, device);
  auto it = streams_.find(key);
  if (it == streams_.end()) {
    it = streams_.emplace(key, writer_.open_stream(run_id_, id, attempt, device)).first;
  }
  if (wait_when_busy_) {
    const auto c = writer_.counters();
    if (c.pushed - c.written + samples.size() > queue_capacity_ / 2) writer_.flush();
  }
  return writer_.push(it->second, samples);
}

void StoreJournal::discard_attempt(std::size_t step, int attempt, const std::string& why) {
  const std::int64_t id = step_id(step);
  writer_.discard_attempt(id, attempt);
  store_.discard_attempt(run_id_, step, attempt);
  std::erase_if(streams_, [&](const auto& entry) {
    return std::get<0>(entry.first) == id && std::get<1>(entry.first) == attempt;
  });
  store_.mark_step_invalidated(run_id_, step, why);
}

void StoreJournal::step_completed(std::size_t step, int attempt, double t_s) {
  const std::int64_t id = step_id(step);
  // Durable samples first, then the step's status: a crash in between leaves the step
  // unfinished and its attempt is redone, never a completed step without its data.
  writer_.commit_step(id, attempt);
  flush_trace();
  std::erase_if(streams_, [&](const auto& entry) { return std::get<0>(entry.first) == id; });
  store_.mark_step_completed(run_id_, step, attempt, store::Stamp::now(t_s));
}

void StoreJournal::step_failed(std::size_t step, int /*attempt*/, double t_s,
                               const std::string& why) {
  flush_trace();
  store_.mark_step_failed(run_id_, step, store::Stamp::now(t_s), why);
}

void StoreJournal::step_skipped(std::size_t step, double /*t_s*/, const std::string& why) {
  store_.mark_step_skipped(run_id_, step, why);
}

void StoreJournal::event(double t_s, EventKind kind, const std::string& source,
                         const std::string& message) {
  store::EventRecord e;
  e.run_id = run_id_;
  e.time_s = t_s;
  e.kind = kind;
  e.source = source;
  e.message = message;
  store_.add_event(e);
}

void StoreJournal::table_telemetry(const core::TableState& state) {
  if (table_decimator_.accept(state.time_s)) store_.add_table_telemetry(run_id_, state);
}

void StoreJournal::table_trace(const core::TableState& state) {
  trace_.push_back(state);
  if (trace_.size() >= kTraceBatch) flush_trace();
}

void StoreJournal::flush_trace() {
  if (trace_.empty()) return;
  store_.add_table_telemetry(run_id_, trace_);
  trace_.clear();
}

void StoreJournal::chamber_telemetry(const core::ChamberState& state) {
  if (chamber_decimator_.accept(state.time_s)) store_.add_chamber_telemetry(run_id_, state);
}

void StoreJournal::run_state(RunState state, double t_s, const std::string& reason) {
  const auto stamp = store::Stamp::now(t_s);
  std::optional<store::Stamp> started;
  std::optional<store::Stamp> ended;
  if (state == RunState::kRunning && !started_) {
    started = stamp;
    started_ = true;
  }
  if (is_terminal(state)) ended = stamp;
  store_.set_run_status(run_id_, std::string(to_string(state)), started, ended, reason);
}

std::string StoreJournal::unit_identified(const std::string& imu, const std::string& model,
                                          const std::string& serial) {
  store::RunUnit unit = store::unit_of_run(store_.database(), run_id_, imu);
  if (!unit.serial.empty() && unit.serial != serial) {
    return fmt::format(
        "{} reports serial {}, but the run is for unit {} ({}): another unit is in the slot", imu,
        serial, unit.serial,
        unit.source == "submitted" ? "given with the run" : "from the station file");
  }
  if (!model.empty()) unit.model = model;
  unit.serial = serial;
  unit.source = "device";
  store::record_run_units(store_.database(), run_id_, {unit});
  return {};
}

}  // namespace calstand::daemon

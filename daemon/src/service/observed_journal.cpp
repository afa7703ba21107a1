#include "daemon/service/observed_journal.hpp"

#include <spdlog/spdlog.h>

#include <string>

#include "core/state_json.hpp"
#include "daemon/service/log_fields.hpp"

namespace calstand::daemon::service {

ObservedJournal::ObservedJournal(RunJournal& inner, EventHub& hub, LiveStatus& live,
                                 std::int64_t run_id, std::chrono::milliseconds telemetry_period)
    : inner_(inner), hub_(hub), live_(live), run_id_(run_id), telemetry_period_(telemetry_period) {}

void ObservedJournal::publish_step(std::size_t step, int attempt, double t_s, const char* status,
                                   const std::string& why) {
  nlohmann::json data = {
      {"run", run_id_}, {"step", step}, {"attempt", attempt}, {"time_s", t_s}, {"status", status}};
  if (!why.empty()) data["reason"] = why;
  hub_.publish("step", std::move(data));
}

void ObservedJournal::step_started(std::size_t step, int attempt, double t_s) {
  inner_.step_started(step, attempt, t_s);
  // The run thread's lines from here on are about this step (the journal's STEP field).
  thread_log_fields().step = step;
  spdlog::info("run {}: step {} started (attempt {})", run_id_, step, attempt);
  publish_step(step, attempt, t_s, "running");
}

bool ObservedJournal::add_samples(std::size_t step, int attempt, const std::string& device,
                                  const std::vector<core::ImuSample>& samples) {
  ImuWindow& w = imu_windows_[device];
  for (const auto& sample : samples) {
    if (w.count == 0) w.first_receive_s = sample.receive_time_s;
    w.last_receive_s = sample.receive_time_s;
    w.gyro_sum_dps += sample.gyro_dps;
    w.accel_sum_mps2 += sample.accel_mps2;
    w.temperature_sum_c += sample.temperature_c;
    ++w.count;
  }
  return inner_.add_samples(step, attempt, device, samples);
}

void ObservedJournal::discard_attempt(std::size_t step, int attempt, const std::string& why) {
  inner_.discard_attempt(step, attempt, why);
  hub_.publish("step", {{"run", run_id_},
                        {"step", step},
                        {"attempt", attempt},
                        {"status", "discarded"},
                        {"reason", why}});
}

void ObservedJournal::step_completed(std::size_t step, int attempt, double t_s) {
  inner_.step_completed(step, attempt, t_s);
  publish_step(step, attempt, t_s, "completed");
}

void ObservedJournal::step_failed(std::size_t step, int attempt, double t_s,
                                  const std::string& why) {
  inner_.step_failed(step, attempt, t_s, why);
  spdlog::warn("run {}: step {} failed (attempt {}): {}", run_id_, step, attempt, why);
  publish_step(step, attempt, t_s, "failed", why);
}

void ObservedJournal::step_skipped(std::size_t step, double t_s, const std::string& why) {
  inner_.step_skipped(step, t_s, why);
  hub_.publish(
      "step",
      {{"run", run_id_}, {"step", step}, {"time_s", t_s}, {"status", "skipped"}, {"reason", why}});
}

void ObservedJournal::event(double t_s, EventKind kind, const std::string& source,
                            const std::string& message) {
  inner_.event(t_s, kind, source, message);
  // Faults and interlocks get their own message type, so a client can watch only those.
  const bool fault = kind == EventKind::kFault || kind == EventKind::kInterlock;
  {
    LogFields fields;
    if (devices_.count(source) != 0) fields.device = source;
    const ScopedLogFields scoped(fields);
    spdlog::log(fault ? spdlog::level::warn : spdlog::level::info, "run {}: {} ({}): {}", run_id_,
                source, to_string(kind), message);
  }
  hub_.publish(fault ? "fault" : "event", {{"run", run_id_},
                                           {"time_s", t_s},
                                           {"kind", std::string(to_string(kind))},
                                           {"source", source},
                                           {"message", message}});
}

void ObservedJournal::table_telemetry(const core::TableState& state) {
  inner_.table_telemetry(state);
}

void ObservedJournal::chamber_telemetry(const core::ChamberState& state) {
  inner_.chamber_telemetry(state);
}

void ObservedJournal::publish_telemetry(const core::TableState& table,
                                        const core::ChamberState& chamber) {
  next_telemetry_ = std::chrono::steady_clock::now() + telemetry_period_;
  live_.update([&](LiveSnapshot& s) {
    s.table = table;
    s.chamber = chamber;
  });
  nlohmann::json imus = nlohmann::json::array();
  for (auto& [device, w] : imu_windows_) {
    nlohmann::json j = {{"device", device}, {"samples", w.count}};
    if (w.count > 0) {
      const double n = static_cast<double>(w.count);
      const Eigen::Vector3d g = w.gyro_sum_dps / n;
      const Eigen::Vector3d a = w.accel_sum_mps2 / n;
      const double span_s = w.last_receive_s - w.first_receive_s;
      j["time_s"] = w.last_receive_s;
      j["rate_hz"] =
          w.count > 1 && span_s > 0 ? nlohmann::json((n - 1.0) / span_s) : nlohmann::json();
      j["gyro_dps"] = {g.x(), g.y(), g.z()};
      j["accel_mps2"] = {a.x(), a.y(), a.z()};
      j["temperature_c"] = w.temperature_sum_c / n;
    }
    imus.push_back(std::move(j));
    w = ImuWindow{};  // an IMU that stops streaming shows 0 samples, not its last means
  }
  hub_.publish("telemetry", {{"run", run_id_},
                             {"table", to_json(table)},
                             {"chamber", to_json(chamber)},
                             {"imus", std::move(imus)}});
}

void ObservedJournal::run_state(RunState state, double t_s, const std::string& reason) {
  inner_.run_state(state, t_s, reason);
  nlohmann::json data = {
      {"run", run_id_}, {"state", std::string(to_string(state))}, {"time_s", t_s}};
  if (!reason.empty()) data["reason"] = reason;
  hub_.publish("run", std::move(data));
}

}  // namespace calstand::daemon::service

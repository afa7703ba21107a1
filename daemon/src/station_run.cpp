#include "daemon/station_run.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <utility>

#include "store/error.hpp"

namespace calstand::daemon {
namespace {

// Table and chamber telemetry rows are kept at most every 0.1 s of station time (the journal
// decimates what the engine hands it); both run paths record at the same rate.
constexpr double kTelemetryPeriodS = 0.1;

}  // namespace

StationRun::StationRun(const core::StationConfig& station, const std::string& db_path,
                       std::int64_t run_id, double start_time_s)
    : run_id_(run_id),
      run_lock_(db_path, run_id),
      config_(station),
      reserve_(db_path, run_id,
               static_cast<std::uint64_t>(station.policy.disk_reserve_mb * 1024.0 * 1024.0)),
      db_(db_path),
      runs_(db_),
      writer_(db_path),
      // Each run of a simulated station records its own noise (run 1 the station seed's), as
      // two recordings of one unit would differ; a resumed run keeps its stream.
      station_(drivers::make_station(config_, start_time_s,
                                     run_id > 0 ? static_cast<std::uint64_t>(run_id - 1) : 0)),
      // A simulated station delivers samples as fast as the CPU allows: the journal waits for
      // the writer rather than counting an overflow no real device would cause.
      journal_(runs_, writer_, run_id, kTelemetryPeriodS, station_->clock().is_virtual()) {}

CampaignResult StationRun::run(const procedures::Plan& plan, const CampaignStart& start,
                               RunJournal& journal,
                               std::function<void(RunEngine&, const Progress&)> on_progress,
                               std::shared_ptr<EngineCommandQueue> commands) {
  EngineOptions options = EngineOptions::from_policy(config_.policy);
  RunEngine* engine_ptr = nullptr;
  options.on_progress = [&](const Progress& p) {
    if (on_progress && engine_ptr) on_progress(*engine_ptr, p);
  };
  RunEngine engine(*station_, journal, plan, options, std::move(commands));
  engine_ptr = &engine;
  CampaignResult result;
  try {
    result.state = engine.run(start.first_step, start.first_attempt, start.skipped_steps);
  } catch (const std::exception& e) {
    if (store::is_storage_error(e)) return end_after_storage_failure(e.what());
    try {
      writer_.flush();  // what was captured before the failure is kept
    } catch (...) {
      // The first failure is the one to report.
    }
    throw;
  } catch (...) {
    try {
      writer_.flush();  // what was captured before the failure is kept
    } catch (...) {
      // The first failure is the one to report.
    }
    throw;
  }
  writer_.flush();
  result.exit_reason = engine.exit_reason();
  result.station_time_s = station_->clock().now_s();
  record_writer_summary(result.station_time_s);
  return result;
}

StationRun::~StationRun() = default;

CampaignResult StationRun::end_after_storage_failure(const std::string& what) {
  // The engine made the station safe before the failure reached here. The capture writer has
  // stopped: what it committed stays, the attempt it was writing is discarded on resume.
  const bool full = store::says_disk_full(what);
  // The reserve's blocks let SQLite write the run's end even on a full disk.
  reserve_.release();
  CampaignResult result;
  result.state = RunState::kInterrupted;
  result.exit_reason =
      fmt::format("storage failed: {}{}", what,
                  full ? "; free space on the database's filesystem, then resume the run" : "");
  result.station_time_s = station_->clock().now_s();
  try {
    store::EventRecord e;
    e.run_id = run_id_;
    e.time_s = result.station_time_s;
    e.kind = store::EventKind::kFault;
    e.source = "store";
    e.message = result.exit_reason;
    runs_.add_event(e);
    runs_.set_run_status(run_id_, std::string(to_string(RunState::kInterrupted)), std::nullopt,
                         std::nullopt, result.exit_reason);
  } catch (const std::exception& e) {
    // Not even the reserve was enough: the run reads `interrupted` anyway once this process
    // has gone (nobody holds its run lock), only without the reason.
    spdlog::error("run {}: recording the storage failure: {}", run_id_, e.what());
  }
  return result;
}

void StationRun::record_writer_summary(double t_s) {
  // The high-water mark set against the capacity is the margin the station had before it would
  // have refused samples: worth knowing before adding IMUs or raising rates. Straight to the
  // store, not through the observed journal: it describes the recording, not the station.
  const auto c = writer_.counters();
  const std::size_t capacity = writer_.queue_capacity();
  store::EventRecord e;
  e.run_id = run_id_;
  e.time_s = t_s;
  e.kind = store::EventKind::kInfo;
  e.source = "capture_writer";
  e.message = fmt::format(
      "capture writer: {} samples stored in {} chunks; queue high-water {} of {} samples; {} "
      "refused",
      c.written, c.chunks, c.queue_high_water, capacity, c.dropped_queue_full);
  e.detail = {{"pushed", c.pushed},
              {"written", c.written},
              {"chunks", c.chunks},
              {"dropped_queue_full", c.dropped_queue_full},
              {"queue_high_water", c.queue_high_water},
              {"queue_capacity", capacity}};
  runs_.add_event(e);
}

}  // namespace calstand::daemon

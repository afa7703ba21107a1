#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "core/station_config.hpp"
#include "daemon/campaign.hpp"
#include "daemon/engine_command.hpp"
#include "daemon/run_engine.hpp"
#include "daemon/store_journal.hpp"
#include "drivers/station.hpp"
#include "procedures/plan.hpp"
#include "store/capture_writer.hpp"
#include "store/database.hpp"
#include "store/disk_space.hpp"
#include "store/run_lock.hpp"
#include "store/run_store.hpp"

namespace calstand::daemon {

/// One recorded run wired to the station, the same way for the foreground `calstand run`
/// (run_campaign()) and calstandd's run service: a database connection and run store, a
/// capture writer, the devices of the station's configuration on a clock starting at the run's
/// station time, the store journal, and the engine with the station's fault policy. Built and
/// run on one thread (the engine's).
class StationRun {
 public:
  /// Opens the database at `db_path` and a capture writer on it, and makes the station's
  /// devices (no device I/O: the engine brings them up). `run_id` is recorded with its steps;
  /// `start_time_s` is where the station clock starts [s] (the last recorded time of a resumed
  /// run). Throws store::DatabaseBusy when another process drives the run already,
  /// store::StoreError for the database, and what drivers::make_station() throws for a station
  /// it cannot make.
  StationRun(const core::StationConfig& station, const std::string& db_path, std::int64_t run_id,
             double start_time_s);
  ~StationRun();

  drivers::Station& station() { return *station_; }
  /// This run's database connection and run store on it (the engine thread's).
  store::Database& database() { return db_; }
  store::RunStore& runs() { return runs_; }
  /// The journal recording the run in the database; wrap it to observe the run as well.
  RunJournal& store_journal() { return journal_; }

  /// Runs `plan` from `start`, recording through `journal` (store_journal() or one that wraps
  /// it). `on_progress` is called on the engine thread at every progress update, with the
  /// engine; operator requests arrive through `commands` (the engine's own queue when null) or
  /// the engine's methods. Blocks until the run ends; the capture writer is flushed however it
  /// ends. A storage failure (the disk full, an I/O error) ends the run `interrupted` with the
  /// reason, after the engine made the station safe: what was committed is intact, the step
  /// that was cut off is redone on resume. Other errors propagate.
  CampaignResult run(const procedures::Plan& plan, const CampaignStart& start, RunJournal& journal,
                     std::function<void(RunEngine&, const Progress&)> on_progress = {},
                     std::shared_ptr<EngineCommandQueue> commands = nullptr);

 private:
  /// Records the capture writer's counters (samples, chunks, queue high-water against its
  /// capacity, refusals) as an info event of the run, source "capture_writer".
  void record_writer_summary(double t_s);

  /// Records the end of a run cut off by a storage failure (`what`), with the reserve's space.
  CampaignResult end_after_storage_failure(const std::string& what);

  std::int64_t run_id_;
  /// Taken first: a run is driven by one process at a time, and one that is driven reads
  /// `running` to others (store/run_lock.hpp); released when the run object goes.
  store::RunLock run_lock_;
  core::StationConfig config_;
  /// Space to record the run's end with when the disk fills (station policy disk_reserve_mb).
  store::DiskReserve reserve_;
  store::Database db_;
  store::RunStore runs_;
  store::CaptureWriter writer_;
  std::unique_ptr<drivers::Station> station_;
  StoreJournal journal_;
};

}  // namespace calstand::daemon

#pragma once
// calstandd --publish: the station's database copied to the fleet's central database in the
// background (fleet/sync.hpp), every few minutes and whenever a run ends.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "daemon/service/event_hub.hpp"
#include "fleet/central_address.hpp"
#include "fleet/sync.hpp"

namespace calstand::daemon::service {

struct PublisherOptions {
  std::string db_path;            ///< the station's database (a connection of its own)
  fleet::CentralAddress central;  ///< checked by fleet::parse_central_address
  fleet::SyncOptions sync;        ///< station name, samples, batch sizes
  double interval_s = 300.0;      ///< between passes when nothing ends [s]
  double max_retry_s = 600.0;     ///< longest wait after failures (doubling from interval) [s]
  /// Throws core::InputError naming the option: a non-positive interval, bad sync options.
  void validate() const;
};

/// Runs a sync pass on a thread of its own: at start, every interval_s, and soon after the
/// event hub says a run ended. Never in the capture path: it reads the database through its
/// own SQLite connection (WAL: the capture writer is never blocked by a reader) and writes only
/// to the central server. A failed pass (server unreachable, refused) is logged with its reason
/// and retried after interval_s, doubling up to max_retry_s; nothing is lost meanwhile, the
/// next pass resumes from the central cursors. Thread safe.
class FleetPublisher {
 public:
  /// Does no I/O; `hub` must outlive the publisher.
  FleetPublisher(PublisherOptions options, EventHub& hub);
  ~FleetPublisher();
  FleetPublisher(const FleetPublisher&) = delete;
  FleetPublisher& operator=(const FleetPublisher&) = delete;

  void start();
  /// Ends the pass in progress at its next transaction boundary and joins the thread.
  void stop();

  /// `{"central", "passes", "failures_in_a_row", "last_success_utc", "last_error",
  ///   "last_report"}` (last_report: fleet::to_json of the last successful pass, or null).
  nlohmann::json status() const;

 private:
  void loop();
  bool pass();  ///< one sync; false when it failed

  PublisherOptions options_;
  EventHub& hub_;
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  long long passes_ = 0;
  int failures_in_a_row_ = 0;
  std::string last_success_utc_;
  std::string last_error_;
  nlohmann::json last_report_;
};

}  // namespace calstand::daemon::service

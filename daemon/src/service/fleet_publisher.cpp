#include "daemon/service/fleet_publisher.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "daemon/run_state.hpp"
#include "store/database.hpp"
#include "store/stamp.hpp"

namespace calstand::daemon::service {

void PublisherOptions::validate() const {
  if (!(interval_s > 0.0)) throw core::InputError("--publish-interval-s", "must be positive");
  if (!(max_retry_s >= interval_s)) {
    throw core::InputError("publisher max retry", "must be at least the interval");
  }
  sync.validate();
}

FleetPublisher::FleetPublisher(PublisherOptions options, EventHub& hub)
    : options_(std::move(options)), hub_(hub) {
  options_.sync.stop_requested = [this] { return stopping_.load(); };
}

FleetPublisher::~FleetPublisher() { stop(); }

void FleetPublisher::start() {
  if (thread_.joinable()) return;
  stopping_ = false;
  thread_ = std::thread([this] { loop(); });
}

void FleetPublisher::stop() {
  stopping_ = true;
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

bool FleetPublisher::pass() {
  try {
    // Connections of its own for each pass: a server restarted in between is simply reached
    // anew, and nothing is held open between passes.
    store::Database station(options_.db_path);
    auto central = fleet::connect_central(options_.central);
    const fleet::SyncReport report = fleet::sync_station(station, *central, options_.sync);
    const fleet::SyncCounts& c = report.copied;
    if (c.rows() > 0 || c.sample_chunks > 0) {
      spdlog::info(
          "publish to {}: {} runs, {} records, {} verdicts, {} fits, {} sample chunks in "
          "{:.2f} s",
          options_.central.display, c.runs, c.calibrations, c.acceptances, c.fits, c.sample_chunks,
          report.seconds);
    }
    std::lock_guard lock(mutex_);
    ++passes_;
    failures_in_a_row_ = 0;
    last_error_.clear();
    last_success_utc_ = store::utc_now_iso8601();
    last_report_ = fleet::to_json(report);
    return true;
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex_);
    ++passes_;
    ++failures_in_a_row_;
    last_error_ = e.what();
    spdlog::warn("publish to {} failed ({} in a row), retried later: {}", options_.central.display,
                 failures_in_a_row_, e.what());
    return false;
  }
}

void FleetPublisher::loop() {
  using clock = std::chrono::steady_clock;
  std::uint64_t seen = hub_.last_seq();
  auto due = clock::now();  // a first pass at once: catch up what was captured offline
  while (!stopping_) {
    if (clock::now() >= due) {
      const bool ok = pass();
      double wait_s = options_.interval_s;
      if (!ok) {
        int failures = 0;
        {
          std::lock_guard lock(mutex_);
          failures = failures_in_a_row_;
        }
        wait_s = std::min(options_.max_retry_s,
                          options_.interval_s * std::pow(2.0, std::min(failures - 1, 20)));
      }
      due = clock::now() +
            std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(wait_s));
    }
    // Wait for the next pass, a run that ends (then publish soon) or stop. The hub wait is
    // bounded so that stop() is seen within a second.
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(due - clock::now());
    const auto slice =
        std::clamp(left, std::chrono::milliseconds(0), std::chrono::milliseconds(1000));
    for (const LiveEvent& e : hub_.wait_after(seen, slice)) {
      seen = e.seq;
      if (e.type == "run" && e.data.contains("state") && e.data["state"].is_string() &&
          has_ended(e.data["state"].get<std::string>())) {
        // A moment later: the event may be published just before the row says so.
        due = std::min(due, clock::now() + std::chrono::seconds(1));
      }
    }
    if (hub_.closed()) {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, slice, [this] { return stopping_.load(); });
    }
  }
}

nlohmann::json FleetPublisher::status() const {
  std::lock_guard lock(mutex_);
  return {{"central", options_.central.display},
          {"passes", passes_},
          {"failures_in_a_row", failures_in_a_row_},
          {"last_success_utc",
           last_success_utc_.empty() ? nlohmann::json() : nlohmann::json(last_success_utc_)},
          {"last_error", last_error_.empty() ? nlohmann::json() : nlohmann::json(last_error_)},
          {"last_report", last_report_}};
}

}  // namespace calstand::daemon::service

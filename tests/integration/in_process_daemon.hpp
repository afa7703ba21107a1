#pragma once
// calstandd in-process for the API tests: hub, run service and API on a free loopback port,
// put together as calstandd_main.cpp does, with the simulated station and the test token.

#include <cstddef>
#include <string>
#include <utility>

#include "core/station_config.hpp"
#include "daemon/api/api_server.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/run_service.hpp"
#include "daemon_test_support.hpp"
#include "sim/sim_world.hpp"

namespace calstand::testing {

class InProcessDaemon {
 public:
  /// `live_messages_kept`: the hub's replay buffer (small to provoke a gap); request bodies
  /// above `max_body_bytes` get 413 (small to test that without sending megabytes).
  explicit InProcessDaemon(
      const std::string& db,
      daemon::service::RecoveryPolicy recovery = daemon::service::RecoveryPolicy::kAuto,
      std::size_t live_messages_kept = 4096, std::size_t max_body_bytes = 64 * 1024)
      : hub_(live_messages_kept),
        service_({sim::load_station_or_default(""), db, recovery}, hub_),
        server_(service_, hub_, options(max_body_bytes)) {
    port_ = server_.start();
    service_.start();
  }
  /// With the API options as given (tokens, TLS, listen host; the port is always a free one).
  InProcessDaemon(const std::string& db, daemon::api::ApiOptions api_options)
      : hub_(4096),
        service_({sim::load_station_or_default(""), db, daemon::service::RecoveryPolicy::kAuto},
                 hub_),
        server_(service_, hub_, with_free_port(std::move(api_options))) {
    port_ = server_.start();
    service_.start();
  }
  /// With `station` (a fixture of several units, serials) instead of the built-in station.
  InProcessDaemon(const std::string& db, core::StationConfig station)
      : hub_(4096),
        service_({std::move(station), db, daemon::service::RecoveryPolicy::kAuto}, hub_),
        server_(service_, hub_, options(64 * 1024)) {
    port_ = server_.start();
    service_.start();
  }
  ~InProcessDaemon() {
    service_.stop("test over");
    server_.stop();
  }
  InProcessDaemon(const InProcessDaemon&) = delete;
  InProcessDaemon& operator=(const InProcessDaemon&) = delete;
  int port() const { return port_; }

 private:
  static daemon::api::ApiOptions with_free_port(daemon::api::ApiOptions o) {
    o.port = 0;
    return o;
  }
  static daemon::api::ApiOptions options(std::size_t max_body_bytes) {
    daemon::api::ApiOptions o;
    o.port = 0;
    o.token = kTestToken;
    o.max_body_bytes = max_body_bytes;
    return o;
  }
  daemon::service::EventHub hub_;
  daemon::service::RunService service_;
  daemon::api::ApiServer server_;
  int port_ = 0;
};

}  // namespace calstand::testing

#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "daemon/service/event_hub.hpp"
#include "daemon/service/run_service.hpp"

namespace calstand::daemon::api {

/// Where and how the control API listens.
struct ApiOptions {
  std::string host = "127.0.0.1";  ///< loopback by default; anything else needs a token
  int port = 8765;                 ///< 0: any free port (tests), see ApiServer::start()
  /// Bearer token the mutating endpoints (POST) require; empty: none (loopback only).
  std::string token;
  std::size_t max_body_bytes = 1 << 20;  ///< larger request bodies get 413
  int threads = 32;  ///< connection threads: each keep-alive client and SSE stream holds one
  /// Live streams (GET /events) served at once; more get 503. Must leave threads for requests.
  int max_streams = 8;

  /// Throws core::InputError naming the field: a host beyond loopback without a token, a port
  /// outside 0..65535, no threads or no body, streams that would take every thread.
  void validate() const;
};

/// The HTTP + JSON control API of calstandd (schemas/api.md) on cpp-httplib, serving a
/// RunService and its live-status hub. Listens on its own thread; stop() (or the destructor)
/// closes live streams and joins it.
class ApiServer {
 public:
  /// `service` and `hub` must outlive the server. Throws as ApiOptions::validate().
  ApiServer(service::RunService& service, service::EventHub& hub, ApiOptions options);
  ~ApiServer();
  ApiServer(const ApiServer&) = delete;
  ApiServer& operator=(const ApiServer&) = delete;

  /// Binds and starts listening; returns the port (the chosen one when options.port is 0).
  /// Throws std::runtime_error naming the address when it cannot bind.
  int start();
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace calstand::daemon::api

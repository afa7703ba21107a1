#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "daemon/api/access.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/run_service.hpp"
#include "fleet/central_address.hpp"

namespace calstand::daemon::api {

/// Where and how the control API listens.
struct ApiOptions {
  std::string host = "127.0.0.1";  ///< loopback by default; anything else needs a token
  int port = 8765;                 ///< 0: any free port (tests), see ApiServer::start()
  /// The single operator token of `--token-file` / `CALSTAND_TOKEN` (named kLegacyTokenName);
  /// empty: none. Adds to `tokens`.
  std::string token;
  /// Named tokens (`--tokens FILE`). With none at all the daemon listens on loopback only and
  /// everything is open; with any, every request that is not a read needs an operator token,
  /// and beyond loopback reads need a token of either role too.
  std::vector<NamedToken> tokens;
  /// TLS certificate chain and private key (PEM files); both or neither. Beyond loopback the
  /// daemon refuses to listen without them unless `allow_plaintext`.
  std::string tls_cert_file;
  std::string tls_key_file;
  bool allow_plaintext = false;
  std::size_t max_body_bytes = 1 << 20;  ///< larger request bodies get 413
  int threads = 32;  ///< connection threads: each keep-alive client and SSE stream holds one
  /// Live streams (GET /events) served at once; more get 503. Must leave threads for requests.
  int max_streams = 8;
  /// A connection that sends nothing for this long while a request is being read (a slow
  /// client trickling its headers gets this much per piece), or that sits idle between
  /// requests, is closed [s].
  int read_timeout_s = 5;
  int keep_alive_timeout_s = 5;
  /// A request's line, headers and body must all arrive within this from its first byte (a
  /// TLS handshake within it from the connection's start); else the connection is closed [s].
  /// Responses, live streams included, are not limited.
  int request_deadline_s = 30;
  /// Connections one client address may hold at once; more are answered 503 and closed.
  int max_connections_per_address = 16;
  /// The fleet's central database to show read-only under /fleet (`--fleet`): checked by
  /// fleet::parse_central_address; none: /fleet answers 404.
  std::optional<fleet::CentralAddress> fleet;
  /// The publisher's state for GET /station/publish (`--publish`: FleetPublisher::status);
  /// empty: that route answers 404. Called from connection threads: must be thread safe.
  std::function<nlohmann::json()> publish_status;

  /// Throws core::InputError naming the option: a host beyond loopback without a token, or
  /// without TLS unless allow_plaintext; half a TLS pair; a token file's names or secrets
  /// given twice; a port outside 0..65535, no threads or no body, streams that would take
  /// every thread.
  void validate() const;
  /// `tokens` and `token` (as kLegacyTokenName) together.
  std::vector<NamedToken> all_tokens() const;
  bool uses_tls() const { return !tls_cert_file.empty(); }
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
  /// Whether it serves https (a certificate was given).
  bool uses_tls() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace calstand::daemon::api

#pragma once

// The `calstand` side of calstandd's control API (schemas/api.md): where the daemon is, the
// token, and JSON requests that turn refusals into errors naming the request.
#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "wire/listen_address.hpp"

namespace httplib {
class Client;
}

namespace calstand::cli {

/// Options every client command takes.
struct DaemonAddress {
  std::string daemon = "127.0.0.1:8765";  ///< [http[s]://]HOST:PORT of calstandd
  std::string token_file;                 ///< else env CALSTAND_TOKEN
  std::string ca_file;                    ///< CA of an https daemon; else env CALSTAND_CA_FILE
  std::string operator_name;              ///< recorded with operator actions; default $USER
};

/// Adds --daemon, --token-file, --ca-file and --operator to `cmd`.
void add_daemon_options(CLI::App& cmd, DaemonAddress& address);

/// A JSON client of one daemon.
class DaemonClient {
 public:
  explicit DaemonClient(const DaemonAddress& address);

  /// GET `path` (with the bearer token, which reads need on a daemon beyond loopback); the
  /// answer's JSON. Throws core::InputError for 4xx answers (their error,
  /// where, and every violation) and std::runtime_error when the daemon cannot be reached.
  nlohmann::json get(const std::string& path) const;
  /// POST `path` with `body` (and the bearer token); as get().
  nlohmann::json post(const std::string& path, const nlohmann::json& body) const;
  /// Reads GET /events until `on_message(type, data)` returns false. A stream that breaks
  /// (the daemon restarting, a network hiccup) is opened again with Last-Event-ID for up to
  /// `reconnect_s` seconds, so nothing the daemon still keeps is missed (a "gap" message says
  /// when something was); throws std::runtime_error naming the daemon when it stays away.
  void stream_events(
      double reconnect_s,
      const std::function<bool(const std::string&, const nlohmann::json&)>& on_message) const;

 private:
  /// A client of the daemon: https with the CA file when the daemon is https (the server's
  /// certificate is always verified), the token on every request.
  std::unique_ptr<httplib::Client> connect(int read_timeout_s) const;

  wire::DaemonEndpoint endpoint_;
  std::string ca_file_;
  std::string token_;
  std::string operator_;
};

}  // namespace calstand::cli

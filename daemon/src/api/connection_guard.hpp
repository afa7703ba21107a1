#pragma once
// What cpp-httplib 0.11 (Debian 12's) lacks, added around it: a deadline for the whole of each
// request (a client trickling its headers a byte at a time within the read timeout is cut once
// the deadline passes) and a cap on the connections one client address holds at once (more are
// answered 503 and closed). The servers below take over httplib's per-connection loop
// (process_and_close_socket, which httplib lets a derived server replace) with the same steps:
// keep-alive, request after request through httplib's own process_request, over a stream of
// ours whose reads know the deadline. Everything else (parsing, routing, responses, streams)
// stays httplib's.

#include <httplib.h>

#include <chrono>
#include <map>
#include <mutex>
#include <string>

namespace calstand::daemon::api {

struct GuardLimits {
  /// The whole request (line, headers, body) must arrive within this [s]; responses, live
  /// streams included, are not limited by it.
  int request_deadline_s = 30;
  /// Connections one client address may hold at once; more are answered 503 and closed.
  int max_connections_per_address = 16;
};

/// Connections held per client address (thread safe).
class AddressCounter {
 public:
  /// Counts one more connection of `address`; false (nothing counted) when it holds `cap`.
  bool admit(const std::string& address, int cap);
  void release(const std::string& address);
  int held(const std::string& address) const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, int> held_;
};

/// httplib::Server with the guard.
class GuardedServer : public httplib::Server {
 public:
  explicit GuardedServer(GuardLimits limits) : limits_(limits) {}

 private:
  bool process_and_close_socket(socket_t sock) override;

  GuardLimits limits_;
  AddressCounter counter_;
};

/// httplib::SSLServer with the guard: the TLS handshake is part of the first request's
/// deadline.
class GuardedSslServer : public httplib::SSLServer {
 public:
  GuardedSslServer(const char* cert_file, const char* key_file, GuardLimits limits)
      : httplib::SSLServer(cert_file, key_file), limits_(limits) {}

 private:
  bool process_and_close_socket(socket_t sock) override;

  GuardLimits limits_;
  AddressCounter counter_;
};

}  // namespace calstand::daemon::api

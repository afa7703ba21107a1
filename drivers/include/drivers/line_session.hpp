#pragma once
// One command-set controller's link: the operations of its CommandSet run over TCP or a serial
// line, one command at a time, with the reply read and parsed, refusals in the controller's own
// words, and the link reopened after a failure (TCP reconnect with backoff, serial reopen).

#include <chrono>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "core/clock.hpp"
#include "drivers/command_set.hpp"
#include "drivers/device_support.hpp"
#include "drivers/line_link.hpp"
#include "drivers/serial_port.hpp"
#include "drivers/tcp_client.hpp"

namespace calstand::drivers::line {

/// The station file's `connection` of a command-set device:
///   {"transport": "tcp", "host": H, "port": P, "timeout_ms": T, "address": A}
///   {"transport": "serial", "path": "/dev/ttyUSB0", "baud": 9600, "parity": "none", ...}
/// `port` and `baud` default to the command set's; `timeout_ms` and `address` override it.
struct LineConnection {
  LineLink link;
  std::chrono::milliseconds timeout{1000};  ///< per reply
  std::string address;                      ///< {address} of the command set's prefix

  /// Validates against the station schema's `line_connection` and reads it. Throws
  /// core::InputError naming `where` + the field (e.g. a TCP port neither given nor defaulted).
  static LineConnection from_json(const nlohmann::json& connection, const CommandSet& set,
                                  const std::string& where);
};

/// What one operation gave.
struct Outcome {
  enum class Kind {
    kOk,         ///< every step answered as expected
    kRefused,    ///< the controller refused (message: its words)
    kTimeout,    ///< no reply in time
    kLinkError,  ///< the link could not be opened, or failed
    kBadReply,   ///< a reply that is not what the step expects
  };
  Kind kind = Kind::kOk;
  Fields fields;        ///< every step's fields, merged
  std::string message;  ///< why, when not kOk: names the command and the controller
  bool ok() const { return kind == Kind::kOk; }
  /// The controller could not be reached (the state's link_lost): a timeout or a link error.
  bool link_lost() const { return kind == Kind::kTimeout || kind == Kind::kLinkError; }
  double number(const std::string& field) const;  ///< throws std::out_of_range when absent
  std::optional<double> maybe_number(const std::string& field) const;
  std::optional<bool> truth(const std::string& field) const;
  std::optional<std::string> text(const std::string& field) const;
};

/// Runs a command set's operations on one link. Not thread safe: the owning driver holds its
/// lock around every call. Counts timeouts, link_errors, bad_replies, refused_commands,
/// stray_bytes and reconnects into the driver's counters, and pushes one event when the link
/// is lost and one when it is back (`who`, e.g. "chamber controller", starts them).
class LineSession {
 public:
  /// The link from the station file's connection (no I/O until the first operation).
  LineSession(CommandSet set, const LineConnection& connection, std::string who, core::Clock& clock,
              FaultCounters& counters, EventQueue& events);
  /// Over a given transport (tests); `timeout` per reply.
  LineSession(CommandSet set, std::unique_ptr<ByteTransport> transport, std::string link_name,
              std::chrono::milliseconds timeout, std::string who, core::Clock& clock,
              FaultCounters& counters, EventQueue& events);
  ~LineSession();
  LineSession(const LineSession&) = delete;
  LineSession& operator=(const LineSession&) = delete;

  const CommandSet& command_set() const { return set_; }
  bool has(std::string_view operation) const { return set_.has(operation); }
  /// Runs `operation` with `args`: each step's line sent, its reply (when the step expects one)
  /// read within the timeout, checked against the set's error replies, then parsed. An operation
  /// the set lacks is a kRefused outcome saying so (no I/O).
  Outcome run(std::string_view operation, const Arguments& args = {});
  /// Opens the link now (configure()); ok or why not.
  Outcome open();
  bool link_down() const { return link_down_; }
  const std::string& link_name() const { return link_name_; }

 private:
  struct Impl;
  Outcome run_step(const Step& step, const Arguments& args, const std::string& operation);
  Outcome fail(Outcome::Kind kind, std::string message);
  void note_link_ok();

  CommandSet set_;
  std::string who_;
  std::string link_name_;
  std::chrono::milliseconds timeout_;
  std::string address_;
  core::Clock& clock_;
  FaultCounters& counters_;
  EventQueue& events_;
  std::unique_ptr<Impl> impl_;
  bool link_down_ = false;
  bool bad_reply_reported_ = false;
};

}  // namespace calstand::drivers::line

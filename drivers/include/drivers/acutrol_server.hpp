#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "drivers/acutrol_protocol.hpp"
#include "drivers/serial_port.hpp"

namespace calstand::sim {
class SimWorld;
}

namespace calstand::drivers {

class PseudoTerminal;

/// Why the controller refused a command (the `ERR <code> <text>` it replies); empty when done.
using Refusal = std::optional<acutrol::ErrorReply>;

/// What a rate table controller does, behind the protocol simulator (AcutrolServer). Axis
/// numbers are the wire's (1 outer, 2 inner; the dispatcher has checked them). Angles [deg],
/// rates [deg/s], accelerations [deg/s^2]. Implementations must be thread safe: the server
/// calls from one thread per client.
class TableServerBackend {
 public:
  virtual ~TableServerBackend() = default;

  /// Reply to `*idn?` (one line, e.g. "CALSTAND,ACUTROL-SIM,0,1.0").
  virtual std::string identity() = 0;

  /// One axis as the controller reports it, read in one go so the fields agree.
  struct AxisReport {
    double angle_deg = 0.0;  ///< wrapped to [-180, 180) [deg]
    double rate_dps = 0.0;   ///< [deg/s]
    acutrol::StatusReply status;
  };
  virtual AxisReport report(int axis) = 0;
  virtual acutrol::InterlockReply interlock(int axis) = 0;

  /// `:mode:position` / `:mode:rate` / `:mode:sine`: selects the mode the next demand is for
  /// (no motion yet).
  virtual Refusal select_mode(int axis, acutrol::WireMode mode) = 0;
  virtual Refusal demand_position(int axis, double angle_deg) = 0;
  virtual Refusal demand_rate(int axis, double rate_dps) = 0;
  /// `:demand:sine`: oscillate about the present angle, amplitude [deg] and frequency [Hz];
  /// refused (201) when the peak rate or acceleration is beyond the `:limit`.
  virtual Refusal demand_sine(int axis, double amplitude_deg, double frequency_hz) = 0;
  /// `:limit N,R,...`: the rate and acceleration limits the controller enforces from now on.
  virtual Refusal set_limits(int axis, double max_rate_dps, double max_accel_dps2) = 0;
  /// Brake to rest and hold. Never refused (it is the safe state), even with an interlock open.
  virtual void stop(int axis) = 0;
  /// `:interlock:close`: refused while the cause that opened it is present.
  virtual Refusal close_interlock(int axis) = 0;
};

/// The reply line (terminator excluded) to one command line: parses it and calls `backend`.
/// Never throws on bad input; errors become `ERR <code> <text>` (acutrol::ErrorCode).
std::string handle_command_line(std::string_view line, TableServerBackend& backend);

/// TableServerBackend over the in-process simulator. Every call locks `world_mutex`, under
/// which another thread advances `world`; both must outlive the backend. Adds the controller
/// behaviour the simulator lacks: the selected mode, software limits (no larger than the
/// simulated axis's own: a lower acceleration limit is recorded but the simulated servo keeps
/// its own profile) and the interlocks.
class SimTableBackend final : public TableServerBackend {
 public:
  SimTableBackend(sim::SimWorld& world, std::mutex& world_mutex);

  std::string identity() override;
  AxisReport report(int axis) override;
  acutrol::InterlockReply interlock(int axis) override;
  Refusal select_mode(int axis, acutrol::WireMode mode) override;
  Refusal demand_position(int axis, double angle_deg) override;
  Refusal demand_rate(int axis, double rate_dps) override;
  Refusal demand_sine(int axis, double amplitude_deg, double frequency_hz) override;
  Refusal set_limits(int axis, double max_rate_dps, double max_accel_dps2) override;
  void stop(int axis) override;
  Refusal close_interlock(int axis) override;

  /// Fault rehearsal: the interlock of `axis` opens because of `why` (e.g. "door open"): the
  /// axis faults and brakes to rest, `:interlock?` answers OPEN, motion is refused until the
  /// cause is cleared (clear_interlock_cause) and `:interlock:close N` is sent.
  void open_interlock(int axis, const std::string& why);
  /// The cause of the open interlock is gone (door shut); the interlock stays open until closed.
  void clear_interlock_cause(int axis);
  /// The limits in force [deg/s, deg/s^2] (as set by `:limit`, initially the axis's own).
  std::pair<double, double> limits(int axis);
  /// Where world time stands now when the world advances in slices behind a wall clock
  /// (SimWorldRunner::clock_s): each query and command first brings the world to it, as a
  /// controller reads its encoder and acts at the moment of the query. Unset: the world's own
  /// time.
  void set_clock(std::function<double()> now_s) { now_s_ = std::move(now_s); }

 private:
  std::function<double()> now_s_;
  /// Advances the world to now_s_() (caller holds the lock).
  void catch_up();
  struct AxisControl {
    acutrol::WireMode selected = acutrol::WireMode::kRest;
    double max_rate_dps = 0.0;
    double max_accel_dps2 = 0.0;
    bool interlock_open = false;
    bool cause_present = false;
    std::string interlock_why;
  };
  /// The controller state of wire axis 1 or 2 (caller holds the lock).
  AxisControl& control(int axis) { return axes_[axis == acutrol::kInnerAxis ? 1 : 0]; }
  /// Refusal when motion is not allowed on the axis (caller holds the lock).
  Refusal motion_refusal(int axis);

  sim::SimWorld& world_;
  std::mutex& mutex_;
  std::array<AxisControl, 2> axes_;
};

struct AcutrolServerOptions {
  std::string bind_host = "127.0.0.1";  ///< IPv4 address to listen on
  std::uint16_t port = 0;               ///< 0: an ephemeral port (see AcutrolServer::port())
  std::size_t max_clients = 8;          ///< further connections are accepted and closed at once
  /// A CR alone ends a line too (controllers whose command sets end lines with CR); the LF of a
  /// CR LF then gives an empty line, which the handler ignores.
  bool cr_ends_line = false;
  std::string reply_terminator = "\n";  ///< appended to every reply
};

/// The protocol simulator: serves the command language over TCP (and, if asked, a
/// pseudo-terminal that plays a serial line) from `backend`, one thread per client plus one
/// accepting. start()/stop() are called from one owning thread; stop() joins every thread and
/// closes every socket (also done by the destructor).
class AcutrolServer {
 public:
  explicit AcutrolServer(TableServerBackend& backend, AcutrolServerOptions options = {});
  /// The reply to one line (terminator excluded), or none: a line protocol other than the
  /// table's served by the same transport (SCPI, whose set commands are not answered).
  /// `overlong`: the line was longer than acutrol::kMaxLineBytes and its text was dropped.
  using LineHandler =
      std::function<std::optional<std::string>(std::string_view line, bool overlong)>;
  /// Serves `handler` instead of the table command language (same transport and threads).
  explicit AcutrolServer(LineHandler handler, AcutrolServerOptions options = {});
  ~AcutrolServer();
  AcutrolServer(const AcutrolServer&) = delete;
  AcutrolServer& operator=(const AcutrolServer&) = delete;

  /// Binds and starts listening. Throws std::runtime_error naming address and OS error.
  void start();
  void stop() noexcept;
  /// The port bound by start() (the ephemeral one when options.port was 0).
  std::uint16_t port() const { return port_; }

  /// Also serves on a new pseudo-terminal; returns the slave path a client opens as its serial
  /// port. Throws std::runtime_error when no pseudo-terminal can be made.
  std::string start_serial();

  /// false: commands are read but never answered (rehearses a hung controller; the client's
  /// response timeout must fire). true again resumes answering.
  void set_answering(bool answering) { answering_ = answering; }
  /// Drops every TCP client connection now (rehearses a broken link); listening goes on.
  void drop_clients();
  /// true: every new TCP connection is closed as soon as it is accepted (a cable pulled: the
  /// clients' reconnects fail) until set_refusing(false). Clients already connected are not
  /// touched (drop_clients() for those).
  void set_refusing(bool refusing) { refusing_ = refusing; }

  std::uint64_t commands_served() const { return commands_; }
  std::size_t client_count() const { return clients_; }

 private:
  struct Session;
  void accept_loop();
  /// Serves one link until it fails or the server stops.
  void serve(ByteTransport& link, const std::atomic<bool>& dropped);
  void reap_sessions(bool all);

  LineHandler handler_;
  AcutrolServerOptions options_;
  int listen_fd_ = -1;
  std::uint16_t port_ = 0;
  std::atomic<bool> stopping_{false};
  std::atomic<bool> answering_{true};
  std::atomic<bool> refusing_{false};
  std::atomic<std::uint64_t> commands_{0};
  std::atomic<std::size_t> clients_{0};
  std::thread accept_thread_;
  std::mutex sessions_mutex_;
  std::vector<std::unique_ptr<Session>> sessions_;
  std::unique_ptr<PseudoTerminal> pty_;
  std::thread pty_thread_;
};

}  // namespace calstand::drivers

#pragma once

#include <linux/can.h>

#include <chrono>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace calstand::drivers {

/// One frame as received, with the kernel's receive time when the transport has one.
struct ReceivedCanFrame {
  can_frame frame{};
  /// CLOCK_REALTIME when the kernel queued the frame [s since the Unix epoch] (SO_TIMESTAMPNS);
  /// closer to the bus than the reader thread's wake-up. Empty when the transport has none.
  std::optional<double> kernel_time_s;
};

/// Outcome of CanTransport::read(). The cyclic path returns this and never throws.
struct CanReadResult {
  enum class Status {
    kFrame,      ///< `frame` holds a frame
    kTimeout,    ///< nothing within the timeout
    kMalformed,  ///< a message that is not a can_frame (wrong size); the link is still up
    kError,      ///< the link failed (`message` says why); further reads will fail too
  };
  Status status = Status::kTimeout;
  ReceivedCanFrame frame;
  std::string message;  ///< why, for kMalformed and kError
};

/// A source and sink of classic CAN frames (SocketCAN, or a test double). Drivers speak to
/// this so that they can be tested without a CAN bus. Not thread safe: one reader at a time
/// (writes from another thread are safe for the socket-based transports below).
class CanTransport {
 public:
  virtual ~CanTransport() = default;
  /// Name for messages ("can0", "socketpair").
  virtual const std::string& name() const = 0;
  /// Opens the link (no-op when open). Throws std::runtime_error saying which link and why.
  virtual void open() = 0;
  virtual void close() noexcept = 0;
  /// Waits up to `timeout` for one frame.
  virtual CanReadResult read(std::chrono::milliseconds timeout) = 0;
  /// Sends one frame within `timeout` (waits while the transmit queue is full). Returns an
  /// empty string on success, otherwise why it failed.
  virtual std::string write(const can_frame& frame, std::chrono::milliseconds timeout) = 0;
  /// Receives only these ids from now on (each an 11-bit id, or 29-bit with CAN_EFF_FLAG);
  /// remote and error frames are not received. Empty: every id. May be called before open().
  /// Throws std::runtime_error when the link refuses them.
  virtual void set_filters(std::span<const canid_t> ids) = 0;
};

/// The receive filters for exact `ids` (CAN_RAW_FILTER semantics: a frame passes when
/// (frame.can_id & can_mask) == (filter.can_id & can_mask) for any filter). Empty `ids`: one
/// filter that passes everything.
std::vector<can_filter> exact_id_filters(std::span<const canid_t> ids);
/// True when `frame_id` passes `filters` by the rule above.
bool passes_filters(canid_t frame_id, std::span<const can_filter> filters);

}  // namespace calstand::drivers

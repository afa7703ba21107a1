#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace calstand::drivers::acutrol {

/// The ACUTROL-style command language of a dual-axis rate table controller (docs/protocols.md,
/// "Rate table command language"). Line based, ASCII: every command is one line ended by '\n'
/// (a '\r' before it is accepted and ignored) and gets exactly one reply line, so a reply that
/// does not come within the response timeout means the link or the controller has failed.
/// Pure functions and value types: no I/O, never throws on bad input.

inline constexpr char kTerminator = '\n';
/// Longest line either side sends or accepts, terminator excluded [bytes]. Longer lines are
/// discarded whole and reported (ERR 103 on the controller, a framing error on the client).
inline constexpr std::size_t kMaxLineBytes = 256;

/// Axis numbers on the wire: 1 = outer, 2 = inner.
inline constexpr int kOuterAxis = 1;
inline constexpr int kInnerAxis = 2;

enum class CommandKind {
  kIdentify,        ///< `*idn?`                  -> identity text
  kModeRate,        ///< `:mode:rate N`           -> OK
  kModePosition,    ///< `:mode:position N`       -> OK
  kDemandRate,      ///< `:demand:rate N,<dps>`   -> OK
  kDemandPosition,  ///< `:demand:position N,<deg>` -> OK
  kModeSine,        ///< `:mode:sine N`           -> OK
  kDemandSine,      ///< `:demand:sine N,<deg>,<Hz>` -> OK (amplitude, frequency)
  kReadPosition,    ///< `:read:pos? N`           -> `<deg>`
  kReadRate,        ///< `:read:rate? N`          -> `<dps>`
  kReadStatus,      ///< `:read:status? N`        -> `<MODE>,<settled>,<INTERLOCK>[,<fault text>]`
  kInterlockQuery,  ///< `:interlock? N`          -> `CLOSED` | `OPEN[,<why>]`
  kInterlockClose,  ///< `:interlock:close N`     -> OK
  kLimit,           ///< `:limit N,R,<dps>,<dps2>` -> OK
  kStop,            ///< `:stop N`                -> OK (brake to rest and hold; never refused)
};

/// One command. `value` is the demand (deg or deg/s; the amplitude [deg] of a sine) or the rate
/// limit [deg/s]; `value2` the acceleration limit [deg/s^2] of `:limit` or the frequency [Hz] of
/// a sine. Unused fields are zero.
struct Command {
  CommandKind kind = CommandKind::kIdentify;
  int axis = 0;  ///< 1 outer, 2 inner; 0 for `*idn?`
  double value = 0.0;
  double value2 = 0.0;
};

/// Error codes of `ERR <code> <text>` replies (data, so client and controller agree).
enum class ErrorCode : int {
  kUnknownCommand = 100,  ///< header not in the language
  kBadArgument = 101,     ///< missing, extra, non-numeric or non-finite argument
  kBadAxis = 102,         ///< axis is not 1 or 2
  kLineTooLong = 103,     ///< more than kMaxLineBytes before the terminator
  kWrongMode = 200,       ///< demand for a mode the axis is not in (send `:mode:...` first)
  kLimitExceeded = 201,   ///< demand or limit beyond what the axis allows
  kAxisFault = 202,       ///< the axis is faulted; motion refused
  kInterlockOpen = 300,   ///< the axis interlock is open; motion refused
  kInterlockCause = 301,  ///< `:interlock:close` refused: the cause is still present
  kController = 500,      ///< anything else the controller refuses
};

/// A value or why there is none (a parse never throws).
template <typename T>
struct Parsed {
  std::optional<T> value;
  std::string error;  ///< empty when value is set
  explicit operator bool() const { return value.has_value(); }
  static Parsed ok(T v) { return {std::move(v), {}}; }
  static Parsed fail(std::string why) { return {std::nullopt, std::move(why)}; }
};

/// A controller's error reply or a client-side parse failure of one.
struct ErrorReply {
  int code = 0;
  std::string text;
};

// ---- client side -------------------------------------------------------------------------

/// The command line, terminator excluded (e.g. `:demand:rate 1,10.000000`). Values are written
/// with 6 decimals (1e-6 deg, 1e-6 deg/s); callers pass finite values.
std::string format_command(const Command& command);

/// What one reply line is: an `ERR <code> <text>` (error set) or anything else (payload).
struct Reply {
  std::optional<ErrorReply> error;
  std::string payload;  ///< the line, trimmed, when it is not an error
};
/// Splits a reply line (terminator removed). A malformed `ERR` line (no numeric code) is still
/// an error, with code 0 and the whole line as text, so a refusal is never taken for data.
Reply parse_reply(std::string_view line);

/// `OK` acknowledgement of a command.
bool is_ok(const Reply& reply);
/// A `:read:pos?` or `:read:rate?` payload: one finite decimal number.
Parsed<double> parse_number(std::string_view payload);

enum class WireMode { kRest, kPosition, kRate, kSine, kFault };
std::string_view to_wire(WireMode mode);

/// `:read:status?` payload.
struct StatusReply {
  WireMode mode = WireMode::kRest;
  bool settled = false;  ///< position: in position; rate: at rate; rest: at rest; sine: running
  bool interlock_open = false;
  std::string fault_text;  ///< empty when the axis has no fault
};
Parsed<StatusReply> parse_status(std::string_view payload);
std::string format_status(const StatusReply& status);

/// `:interlock?` payload.
struct InterlockReply {
  bool open = false;
  std::string why;  ///< the cause when open (may be empty)
};
Parsed<InterlockReply> parse_interlock(std::string_view payload);
std::string format_interlock(const InterlockReply& interlock);

// ---- controller side ---------------------------------------------------------------------

/// Parses one command line (terminator removed). Headers are case-insensitive; blanks around
/// arguments are ignored. Failures carry the ErrorCode the controller replies with.
struct CommandParse {
  std::optional<Command> command;
  ErrorReply error;  ///< set when command is empty
};
CommandParse parse_command(std::string_view line);

/// `ERR <code> <text>`, the text made one bounded line (control characters become blanks).
std::string format_error(int code, std::string_view text);
inline std::string format_error(ErrorCode code, std::string_view text) {
  return format_error(static_cast<int>(code), text);
}
/// A number reply with 6 decimals.
std::string format_number(double value);
/// Text made safe for one reply line: control characters to blanks, at most `max_bytes`.
std::string sanitize_text(std::string_view text, std::size_t max_bytes = 160);

// ---- framing -----------------------------------------------------------------------------

/// Splits a byte stream into lines: '\n' ends a line, a '\r' before it is dropped. A line that
/// grows beyond kMaxLineBytes is discarded up to its terminator and reported once as an
/// overlong line, so a stream of garbage cannot grow memory. Not thread safe.
class LineAssembler {
 public:
  struct Line {
    std::string text;
    bool overlong = false;  ///< the line was too long and its text is dropped
  };
  void push(std::span<const std::uint8_t> bytes);
  void push(std::string_view bytes);
  /// The next complete line, oldest first.
  std::optional<Line> next();
  /// Drops everything buffered (after a timeout the stream is out of step).
  void clear();
  std::size_t buffered_bytes() const { return partial_.size(); }

 private:
  std::string partial_;
  bool discarding_ = false;
  std::deque<Line> lines_;  // complete lines not yet taken
};

}  // namespace calstand::drivers::acutrol

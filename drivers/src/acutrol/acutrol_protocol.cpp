#include "drivers/acutrol_protocol.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <vector>

namespace calstand::drivers::acutrol {
namespace {

/// How a command's arguments look after the header.
enum class Args {
  kNone,       // *idn?
  kAxis,       // N
  kAxisValue,  // N,<number>
  kAxisLimit,  // N,R,<number>,<number>
  kAxisPair,   // N,<number>,<number>
};

struct CommandSpec {
  CommandKind kind;
  std::string_view header;  // lower case
  Args args;
};

// The language as data: format and parse both read this table.
constexpr std::array kCommands{
    CommandSpec{CommandKind::kIdentify, "*idn?", Args::kNone},
    CommandSpec{CommandKind::kModeRate, ":mode:rate", Args::kAxis},
    CommandSpec{CommandKind::kModePosition, ":mode:position", Args::kAxis},
    CommandSpec{CommandKind::kDemandRate, ":demand:rate", Args::kAxisValue},
    CommandSpec{CommandKind::kDemandPosition, ":demand:position", Args::kAxisValue},
    CommandSpec{CommandKind::kModeSine, ":mode:sine", Args::kAxis},
    CommandSpec{CommandKind::kDemandSine, ":demand:sine", Args::kAxisPair},
    CommandSpec{CommandKind::kReadPosition, ":read:pos?", Args::kAxis},
    CommandSpec{CommandKind::kReadRate, ":read:rate?", Args::kAxis},
    CommandSpec{CommandKind::kReadStatus, ":read:status?", Args::kAxis},
    CommandSpec{CommandKind::kInterlockQuery, ":interlock?", Args::kAxis},
    CommandSpec{CommandKind::kInterlockClose, ":interlock:close", Args::kAxis},
    CommandSpec{CommandKind::kLimit, ":limit", Args::kAxisLimit},
    CommandSpec{CommandKind::kStop, ":stop", Args::kAxis},
};

const CommandSpec& spec_of(CommandKind kind) {
  for (const auto& s : kCommands) {
    if (s.kind == kind) return s;
  }
  return kCommands.front();  // unreachable: every kind is in the table
}

bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && (is_blank(s.front()) || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (is_blank(s.back()) || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool iequals(std::string_view a, std::string_view b) { return lower(a) == lower(b); }

std::vector<std::string_view> split_commas(std::string_view s) {
  std::vector<std::string_view> parts;
  for (;;) {
    const auto comma = s.find(',');
    parts.push_back(trim(s.substr(0, comma)));
    if (comma == std::string_view::npos) break;
    s.remove_prefix(comma + 1);
  }
  return parts;
}

Parsed<double> parse_finite(std::string_view text, std::string_view what) {
  text = trim(text);
  if (text.empty()) return Parsed<double>::fail(fmt::format("{} is missing", what));
  // from_chars refuses a leading '+', which people type; accept it.
  if (text.front() == '+') text.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size()) {
    return Parsed<double>::fail(
        fmt::format("{} '{}' is not a number", what, sanitize_text(text, 40)));
  }
  if (!std::isfinite(v)) {
    return Parsed<double>::fail(
        fmt::format("{} '{}' is not finite", what, sanitize_text(text, 40)));
  }
  return Parsed<double>::ok(v);
}

CommandParse fail(ErrorCode code, std::string text) {
  return {std::nullopt, {static_cast<int>(code), std::move(text)}};
}

}  // namespace

// ---- client side -------------------------------------------------------------------------

std::string format_command(const Command& c) {
  const auto& spec = spec_of(c.kind);
  switch (spec.args) {
    case Args::kNone:
      return std::string(spec.header);
    case Args::kAxis:
      return fmt::format("{} {}", spec.header, c.axis);
    case Args::kAxisValue:
      return fmt::format("{} {},{:.6f}", spec.header, c.axis, c.value);
    case Args::kAxisLimit:
      return fmt::format("{} {},R,{:.6f},{:.6f}", spec.header, c.axis, c.value, c.value2);
    case Args::kAxisPair:
      return fmt::format("{} {},{:.6f},{:.6f}", spec.header, c.axis, c.value, c.value2);
  }
  return std::string(spec.header);
}

Reply parse_reply(std::string_view line) {
  line = trim(line);
  Reply r;
  if (line.size() >= 3 && iequals(line.substr(0, 3), "err") &&
      (line.size() == 3 || is_blank(line[3]))) {
    std::string_view rest = trim(line.substr(3));
    const auto blank = std::min(rest.find(' '), rest.size());
    int code = 0;
    const auto [end, ec] = std::from_chars(rest.data(), rest.data() + blank, code);
    if (ec == std::errc() && end == rest.data() + blank && blank > 0) {
      r.error = ErrorReply{code, std::string(trim(rest.substr(blank)))};
    } else {
      r.error = ErrorReply{0, sanitize_text(line)};
    }
    return r;
  }
  r.payload = std::string(line);
  return r;
}

bool is_ok(const Reply& reply) { return !reply.error && iequals(reply.payload, "ok"); }

Parsed<double> parse_number(std::string_view payload) { return parse_finite(payload, "reply"); }

std::string_view to_wire(WireMode mode) {
  switch (mode) {
    case WireMode::kRest:
      return "REST";
    case WireMode::kPosition:
      return "POSITION";
    case WireMode::kRate:
      return "RATE";
    case WireMode::kSine:
      return "SINE";
    case WireMode::kFault:
      return "FAULT";
  }
  return "REST";
}

Parsed<StatusReply> parse_status(std::string_view payload) {
  // MODE,settled,INTERLOCK[,fault text]: the text is last because it may hold commas.
  std::vector<std::string_view> head;
  std::string_view rest = trim(payload);
  for (int i = 0; i < 3; ++i) {
    const auto comma = rest.find(',');
    head.push_back(trim(rest.substr(0, comma)));
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
    if (comma == std::string_view::npos) break;
  }
  const auto bad = [&](std::string_view why) {
    return Parsed<StatusReply>::fail(
        fmt::format("status reply '{}': {}", sanitize_text(payload, 60), why));
  };
  if (head.size() < 3) return bad("expected MODE,settled,INTERLOCK[,fault text]");
  StatusReply s;
  bool mode_known = false;
  for (const auto m :
       {WireMode::kRest, WireMode::kPosition, WireMode::kRate, WireMode::kSine, WireMode::kFault}) {
    if (iequals(head[0], to_wire(m))) {
      s.mode = m;
      mode_known = true;
    }
  }
  if (!mode_known) return bad("mode is not REST, POSITION, RATE, SINE or FAULT");
  if (head[1] != "0" && head[1] != "1") return bad("settled flag is not 0 or 1");
  s.settled = head[1] == "1";
  if (iequals(head[2], "open")) {
    s.interlock_open = true;
  } else if (!iequals(head[2], "closed")) {
    return bad("interlock is not OPEN or CLOSED");
  }
  s.fault_text = std::string(trim(rest));
  return Parsed<StatusReply>::ok(std::move(s));
}

std::string format_status(const StatusReply& s) {
  std::string out = fmt::format("{},{},{}", to_wire(s.mode), s.settled ? 1 : 0,
                                s.interlock_open ? "OPEN" : "CLOSED");
  if (!s.fault_text.empty()) out += "," + sanitize_text(s.fault_text);
  return out;
}

Parsed<InterlockReply> parse_interlock(std::string_view payload) {
  payload = trim(payload);
  const auto comma = payload.find(',');
  const auto state = trim(payload.substr(0, comma));
  InterlockReply r;
  if (iequals(state, "closed")) return Parsed<InterlockReply>::ok(r);
  if (iequals(state, "open")) {
    r.open = true;
    if (comma != std::string_view::npos) r.why = std::string(trim(payload.substr(comma + 1)));
    return Parsed<InterlockReply>::ok(std::move(r));
  }
  return Parsed<InterlockReply>::fail(
      fmt::format("interlock reply '{}' is not CLOSED or OPEN[,why]", sanitize_text(payload, 60)));
}

std::string format_interlock(const InterlockReply& i) {
  if (!i.open) return "CLOSED";
  return i.why.empty() ? std::string("OPEN") : "OPEN," + sanitize_text(i.why);
}

// ---- controller side ---------------------------------------------------------------------

CommandParse parse_command(std::string_view line) {
  line = trim(line);
  if (line.empty()) return fail(ErrorCode::kUnknownCommand, "empty command");
  if (line.size() > kMaxLineBytes) {
    return fail(ErrorCode::kLineTooLong, fmt::format("line longer than {} bytes", kMaxLineBytes));
  }
  const auto blank = std::min(line.find_first_of(" \t"), line.size());
  const std::string header = lower(line.substr(0, blank));
  const std::string_view args = trim(line.substr(blank));
  const CommandSpec* spec = nullptr;
  for (const auto& s : kCommands) {
    if (s.header == header) spec = &s;
  }
  if (spec == nullptr) {
    return fail(ErrorCode::kUnknownCommand,
                fmt::format("unknown command '{}'", sanitize_text(header, 40)));
  }
  Command c;
  c.kind = spec->kind;
  if (spec->args == Args::kNone) {
    if (!args.empty())
      return fail(ErrorCode::kBadArgument, fmt::format("{} takes no argument", spec->header));
    return {c, {}};
  }
  const auto parts = split_commas(args);
  const std::size_t expected = spec->args == Args::kAxis        ? 1
                               : spec->args == Args::kAxisValue ? 2
                               : spec->args == Args::kAxisPair  ? 3
                                                                : 4;
  if (parts.size() != expected || parts.front().empty()) {
    static constexpr std::array kUsage{"", "N", "N,<value>", "N,R,<rate dps>,<accel dps2>",
                                       "N,<amplitude deg>,<frequency Hz>"};
    return fail(ErrorCode::kBadArgument, fmt::format("{} expects {}", spec->header,
                                                     kUsage[static_cast<std::size_t>(spec->args)]));
  }
  int axis = 0;
  const auto a = parts[0];
  const auto [end, ec] = std::from_chars(a.data(), a.data() + a.size(), axis);
  if (ec != std::errc() || end != a.data() + a.size() ||
      (axis != kOuterAxis && axis != kInnerAxis)) {
    return fail(ErrorCode::kBadAxis,
                fmt::format("axis '{}' is not 1 (outer) or 2 (inner)", sanitize_text(a, 20)));
  }
  c.axis = axis;
  if (spec->args == Args::kAxisValue) {
    const auto v = parse_finite(parts[1], c.kind == CommandKind::kDemandRate ? "rate" : "position");
    if (!v) return fail(ErrorCode::kBadArgument, v.error);
    c.value = *v.value;
  } else if (spec->args == Args::kAxisLimit) {
    if (!iequals(parts[1], "r")) {
      return fail(ErrorCode::kBadArgument,
                  fmt::format("limit type '{}' is not R (rate and acceleration)",
                              sanitize_text(parts[1], 20)));
    }
    const auto rate = parse_finite(parts[2], "rate limit");
    if (!rate) return fail(ErrorCode::kBadArgument, rate.error);
    const auto acc = parse_finite(parts[3], "acceleration limit");
    if (!acc) return fail(ErrorCode::kBadArgument, acc.error);
    if (!(*rate.value > 0.0) || !(*acc.value > 0.0)) {
      return fail(ErrorCode::kBadArgument, "limits must be positive");
    }
    c.value = *rate.value;
    c.value2 = *acc.value;
  } else if (spec->args == Args::kAxisPair) {
    const auto amplitude = parse_finite(parts[1], "amplitude");
    if (!amplitude) return fail(ErrorCode::kBadArgument, amplitude.error);
    const auto frequency = parse_finite(parts[2], "frequency");
    if (!frequency) return fail(ErrorCode::kBadArgument, frequency.error);
    if (!(*amplitude.value > 0.0) || !(*frequency.value > 0.0)) {
      return fail(ErrorCode::kBadArgument, "amplitude and frequency must be positive");
    }
    c.value = *amplitude.value;
    c.value2 = *frequency.value;
  }
  return {c, {}};
}

std::string sanitize_text(std::string_view text, std::size_t max_bytes) {
  std::string out;
  out.reserve(std::min(text.size(), max_bytes));
  for (const char ch : text) {
    if (out.size() >= max_bytes) break;
    const auto u = static_cast<unsigned char>(ch);
    // Keep printable ASCII only: a byte that is not cannot break the peer's framing or terminal.
    out.push_back(u >= 0x20 && u < 0x7f ? ch : ' ');
  }
  return out;
}

std::string format_error(int code, std::string_view text) {
  return fmt::format("ERR {} {}", code, sanitize_text(text));
}

std::string format_number(double value) { return fmt::format("{:.6f}", value); }

// ---- framing -----------------------------------------------------------------------------

void LineAssembler::push(std::span<const std::uint8_t> bytes) {
  for (const std::uint8_t b : bytes) {
    const char c = static_cast<char>(b);
    if (c == kTerminator) {
      if (discarding_) {
        lines_.push_back({{}, true});
      } else {
        if (!partial_.empty() && partial_.back() == '\r') partial_.pop_back();
        lines_.push_back({std::move(partial_), false});
      }
      partial_.clear();
      discarding_ = false;
      continue;
    }
    if (discarding_) continue;
    // One byte of slack for the '\r' of a "\r\n" ending a line of exactly kMaxLineBytes.
    if (partial_.size() >= kMaxLineBytes + 1) {
      discarding_ = true;
      partial_.clear();
      continue;
    }
    partial_.push_back(c);
  }
}

void LineAssembler::push(std::string_view bytes) {
  push(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(bytes.data()),
                                     bytes.size()));
}

std::optional<LineAssembler::Line> LineAssembler::next() {
  if (lines_.empty()) return std::nullopt;
  Line l = std::move(lines_.front());
  lines_.pop_front();
  // The slack byte above admitted one byte too many when it was not a '\r'.
  if (!l.overlong && l.text.size() > kMaxLineBytes) return Line{{}, true};
  return l;
}

void LineAssembler::clear() {
  partial_.clear();
  lines_.clear();
  discarding_ = false;
}

}  // namespace calstand::drivers::acutrol

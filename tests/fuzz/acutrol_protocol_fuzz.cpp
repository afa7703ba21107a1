// libFuzzer target: arbitrary bytes as the table command language, both sides of the link.
// The bytes are framed by the LineAssembler (in fuzzer-chosen chunks) and every line goes
//   - to every client-side reply parser (parse_reply, is_ok, parse_number, parse_status,
//     parse_interlock), whose successes must survive a format/parse round trip, and
//   - to the controller: parse_command and handle_command_line against a SimTableBackend over a
//     table-only SimWorld of the default station, whose reply must be exactly one line of
//     printable ASCII, at most kMaxLineBytes, that the client's own parsers read as the answer
//     to that command (same error code, the number or status the backend reports).
// A line starting with byte 0x01, 0x02 or 0x03 is a directive instead: advance the world, open
// an axis's interlock (with the rest of the line as its cause), clear the interlock's cause.
// Any broken invariant aborts.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/acutrol_protocol.hpp"
#include "drivers/acutrol_server.hpp"
#include "sim/sim_world.hpp"

namespace {

using namespace calstand::drivers;
using namespace calstand::drivers::acutrol;

void check(bool ok) {
  if (!ok) std::abort();
}

const calstand::core::StationConfig& table_only_station() {
  static const calstand::core::StationConfig config = [] {
    auto c = calstand::sim::default_station();
    c.imus.clear();  // IMU samples would only fill buffers nobody drains
    return c;
  }();
  return config;
}

bool printable_line(std::string_view s) {
  if (s.empty() || s.size() > kMaxLineBytes) return false;
  for (const char ch : s) {
    const auto u = static_cast<unsigned char>(ch);
    if (u < 0x20 || u >= 0x7f) return false;
  }
  return true;
}

// Every client-side parser on one line: no crash, and what parses formats back to the same.
void client_parsers(std::string_view line) {
  const Reply reply = parse_reply(line);
  if (reply.error) {
    check(reply.payload.empty());
    check(!is_ok(reply));
  }
  const std::string_view payload = reply.payload;
  if (const auto n = parse_number(payload))
    check(std::isfinite(*n.value));
  else
    check(!n.error.empty());
  if (const auto s = parse_status(payload)) {
    const auto again = parse_status(format_status(*s.value));
    check(again && again.value->mode == s.value->mode && again.value->settled == s.value->settled &&
          again.value->interlock_open == s.value->interlock_open);
  } else {
    check(!s.error.empty());
  }
  if (const auto i = parse_interlock(payload)) {
    const auto again = parse_interlock(format_interlock(*i.value));
    check(again && again.value->open == i.value->open);
    check(i.value->open || i.value->why.empty());
  } else {
    check(!i.error.empty());
  }
}

// The controller's parse: a command is well formed, and (for values a client would send) the
// line the client formats for it parses to the same command.
void command_parser(std::string_view line) {
  const CommandParse p = parse_command(line);
  if (!p.command) {
    check(p.error.code != 0 && !p.error.text.empty());
    return;
  }
  const Command& c = *p.command;
  check(c.kind == CommandKind::kIdentify ? c.axis == 0
                                         : (c.axis == kOuterAxis || c.axis == kInnerAxis));
  check(std::isfinite(c.value) && std::isfinite(c.value2));
  if (c.kind == CommandKind::kLimit) check(c.value > 0.0 && c.value2 > 0.0);
  const bool sendable = std::abs(c.value) <= 1e9 && std::abs(c.value2) <= 1e9 &&
                        (c.kind != CommandKind::kLimit || (c.value >= 1e-6 && c.value2 >= 1e-6));
  if (!sendable) return;
  const CommandParse again = parse_command(format_command(c));
  check(again.command && again.command->kind == c.kind && again.command->axis == c.axis &&
        std::abs(again.command->value - c.value) <= 1e-6 &&
        std::abs(again.command->value2 - c.value2) <= 1e-6);
}

// The controller's reply to one line, read back by the client.
void server_reply(std::string_view line, SimTableBackend& backend) {
  const std::string reply = handle_command_line(line, backend);
  check(printable_line(reply));
  const Reply r = parse_reply(reply);
  const CommandParse p = parse_command(line);
  if (!p.command) {
    check(r.error && r.error->code == p.error.code);
    return;
  }
  const Command& c = *p.command;
  switch (c.kind) {
    case CommandKind::kIdentify:
      check(!r.error);
      break;
    case CommandKind::kReadPosition:
    case CommandKind::kReadRate: {
      // The world does not move between the command and this report.
      const auto report = backend.report(c.axis);
      const double truth =
          c.kind == CommandKind::kReadPosition ? report.angle_deg : report.rate_dps;
      const auto n = parse_number(r.payload);
      check(!r.error && n && std::abs(*n.value - truth) <= 1e-6 * (1.0 + std::abs(truth)));
      break;
    }
    case CommandKind::kReadStatus: {
      const auto report = backend.report(c.axis);
      const auto s = parse_status(r.payload);
      check(!r.error && s && s.value->mode == report.status.mode &&
            s.value->settled == report.status.settled &&
            s.value->interlock_open == report.status.interlock_open);
      break;
    }
    case CommandKind::kInterlockQuery: {
      const auto i = parse_interlock(r.payload);
      check(!r.error && i && i.value->open == backend.interlock(c.axis).open);
      break;
    }
    case CommandKind::kStop:
      check(is_ok(r));  // the safe state is never refused
      break;
    default:
      // An acknowledgement or a refusal with a code of the language, never anything else.
      check(is_ok(r) || (r.error && r.error->code >= 100 && r.error->code <= 500));
      break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view all(reinterpret_cast<const char*>(data), size);
  command_parser(all);  // unframed, so lines longer than any framed one are tried too
  client_parsers(all);

  // Frame the rest in chunks of 1..64 bytes (the first byte says), as reads split a stream.
  const std::size_t chunk = 1 + data[0] % 64;
  LineAssembler assembler;
  std::vector<LineAssembler::Line> lines;
  std::size_t terminators = 0;
  for (std::size_t at = 1; at < size; at += chunk) {
    const auto piece = all.substr(at, chunk);
    for (const char ch : piece) terminators += ch == kTerminator ? 1 : 0;
    assembler.push(piece);
    check(assembler.buffered_bytes() <= kMaxLineBytes + 1);
    while (auto line = assembler.next()) lines.push_back(std::move(*line));
  }
  // Every terminator ends exactly one line; each line is what was sent between terminators
  // (one '\r' before the terminator dropped), or overlong when that is over kMaxLineBytes.
  check(lines.size() == terminators);
  std::size_t from = 1;
  for (const auto& line : lines) {
    const std::size_t end = all.find(kTerminator, from);
    std::string_view sent = all.substr(from, end - from);
    from = end + 1;
    if (!sent.empty() && sent.back() == '\r') sent.remove_suffix(1);
    if (sent.size() > kMaxLineBytes) {
      check(line.overlong && line.text.empty());
    } else {
      check(!line.overlong && line.text == sent);
    }
  }

  std::mutex world_mutex;
  calstand::sim::SimWorld world(table_only_station());
  SimTableBackend backend(world, world_mutex);
  double sim_budget_s = 5.0;  // bounds the time one input spends in the physics (speed)
  for (const auto& line : lines) {
    if (line.overlong) continue;
    const std::string_view text = line.text;
    if (!text.empty() && text[0] >= 1 && text[0] <= 3) {
      const int axis = text.size() > 1 && (text[1] & 1) ? kInnerAxis : kOuterAxis;
      if (text[0] == 1) {
        const double dt = text.size() > 1 ? static_cast<unsigned char>(text[1]) * 0.01 : 0.01;
        const double step = std::min(dt, sim_budget_s);
        sim_budget_s -= step;
        std::lock_guard lock(world_mutex);
        world.advance(step);
      } else if (text[0] == 2) {
        backend.open_interlock(axis,
                               std::string(text.substr(std::min<std::size_t>(2, text.size()))));
      } else {
        backend.clear_interlock_cause(axis);
      }
      continue;
    }
    client_parsers(text);
    command_parser(text);
    server_reply(text, backend);
  }
  return 0;
}

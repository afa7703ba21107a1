#include "wire/sse_encoder.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace calstand::wire {
namespace {

// An id or a type is one field on one line: a line break would end it (and start another
// field), NUL makes a reader ignore an id.
void check_one_line(std::string_view field, std::string_view value) {
  if (value.find_first_of(std::string_view("\r\n\0", 3)) != std::string_view::npos) {
    throw std::invalid_argument(
        fmt::format("server-sent event {} '{}' holds a line break or NUL", field, value));
  }
}

}  // namespace

std::string encode_sse_event(const SseEvent& event) {
  check_one_line("id", event.id);
  check_one_line("type", event.type);
  std::string out;
  out.reserve(event.data.size() + event.id.size() + event.type.size() + 24);
  if (!event.id.empty()) out.append("id: ").append(event.id).append("\n");
  if (!event.type.empty()) out.append("event: ").append(event.type).append("\n");
  // Each line of the data on a data line of its own; the reader joins them with LF, so CR and
  // CRLF in the data come back as LF.
  std::string_view rest = event.data;
  for (;;) {
    const std::size_t eol = rest.find_first_of("\r\n");
    out.append("data: ").append(rest.substr(0, eol)).append("\n");
    if (eol == std::string_view::npos) break;
    const bool crlf = rest[eol] == '\r' && eol + 1 < rest.size() && rest[eol + 1] == '\n';
    rest.remove_prefix(eol + (crlf ? 2 : 1));
  }
  out += '\n';
  return out;
}

std::string encode_sse_comment(std::string_view text) {
  std::string line(text);
  for (char& c : line) {
    if (c == '\r' || c == '\n') c = ' ';
  }
  return ": " + line + "\n\n";
}

std::string encode_sse_retry(unsigned retry_ms) { return fmt::format("retry: {}\n\n", retry_ms); }

}  // namespace calstand::wire

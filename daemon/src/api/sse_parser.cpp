#include "daemon/api/sse_parser.hpp"

namespace calstand::daemon::api {

bool SseParser::feed(std::string_view piece) {
  buffer_.append(piece);
  std::size_t start = 0;
  for (std::size_t end; (end = buffer_.find("\n\n", start)) != std::string::npos; start = end + 2) {
    SseMessage m;
    for (std::size_t pos = start; pos < end;) {
      std::size_t eol = buffer_.find('\n', pos);
      if (eol == std::string::npos || eol > end) eol = end;
      const std::string_view line(buffer_.data() + pos, eol - pos);
      if (line.rfind("id: ", 0) == 0) m.id = line.substr(4);
      if (line.rfind("event: ", 0) == 0) m.type = line.substr(7);
      if (line.rfind("data: ", 0) == 0) m.data = line.substr(6);
      pos = eol + 1;
    }
    if (!m.type.empty() && !on_message_(m)) {
      buffer_.erase(0, end + 2);
      return false;
    }
  }
  buffer_.erase(0, start);
  return true;
}

}  // namespace calstand::daemon::api

#include <charconv>
#include <stdexcept>
#include <string>

#include "store/migration_blocks.hpp"

namespace calstand::store {

std::vector<Migration> parse_migrations(std::string_view text) {
  static constexpr std::string_view kMarker = "-- migration ";
  std::vector<Migration> out;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(pos, end - pos);
    if (line.starts_with(kMarker)) {
      const std::string_view rest = line.substr(kMarker.size());
      Migration m;
      const auto [ptr, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), m.version);
      if (ec != std::errc() || ptr == rest.data() + rest.size() || *ptr != ':') {
        throw std::logic_error("schema: malformed migration marker: " + std::string(line));
      }
      std::string_view title = rest.substr(static_cast<std::size_t>(ptr - rest.data()) + 1);
      while (title.starts_with(' ')) title.remove_prefix(1);
      m.title = std::string(title);
      if (m.version != static_cast<int>(out.size()) + 1) {
        throw std::logic_error("schema: migration " + std::to_string(m.version) +
                               " out of order; expected " + std::to_string(out.size() + 1));
      }
      out.push_back(std::move(m));
    } else if (!out.empty()) {
      out.back().sql.append(line).append("\n");
    }
    pos = end + 1;
  }
  return out;
}

}  // namespace calstand::store

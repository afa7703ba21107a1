#include "core/csv_reader.hpp"

#include <fast_float/fast_float.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <set>

#include "core/error.hpp"

namespace calstand::core {
namespace {

bool blank(char c) { return c == ' ' || c == '\t'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

// from_chars refuses a leading '+'; CSV writers (and C's printf("%+g")) use one.
std::string_view drop_plus(std::string_view t) {
  if (t.size() > 1 && t.front() == '+' && t[1] != '-' && t[1] != '+') t.remove_prefix(1);
  return t;
}

}  // namespace

std::optional<double> parse_csv_number(std::string_view text) {
  const std::string_view t = drop_plus(text);
  double v = 0.0;
  const auto [ptr, ec] = fast_float::from_chars(t.data(), t.data() + t.size(), v);
  if (t.empty() || ec != std::errc() || ptr != t.data() + t.size() || !std::isfinite(v)) {
    return std::nullopt;
  }
  return v;
}

CsvReader::CsvReader(const std::filesystem::path& path, CsvOptions options)
    : file_(path.string()), options_(options) {
  if (options_.block_bytes < 64) options_.block_bytes = 64;
  fd_ = ::open(file_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw InputError(file_, "cannot open the file");
  buffer_.resize(options_.block_bytes);
  std::string_view line;
  if (!read_line(line)) throw InputError(file_, "empty file: no header");
  if (line.starts_with("\xEF\xBB\xBF")) line.remove_prefix(3);  // UTF-8 byte order mark
  header_ = std::string(trim(line));
  split(line);
  columns_.assign(fields_.begin(), fields_.end());
}

CsvReader::~CsvReader() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<std::size_t> CsvReader::column(std::string_view name) const {
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    if (columns_[i] == name) return i;
  }
  return std::nullopt;
}

void CsvReader::require_unique_columns() const {
  std::set<std::string_view> seen;
  for (const std::string& c : columns_) {
    if (!seen.insert(c).second) {
      throw InputError(file_ + ":1", fmt::format("column '{}' appears twice in the header", c));
    }
  }
}

std::string CsvReader::where() const { return fmt::format("{}:{}", file_, line_); }

// The next line without its line end (LF or CR LF), or false at the end of the file. The view
// points into buffer_ and lives until the next call.
bool CsvReader::read_line(std::string_view& line) {
  for (;;) {
    const char* start = buffer_.data() + begin_;
    const auto* nl = static_cast<const char*>(std::memchr(start, '\n', end_ - begin_));
    if (nl != nullptr || (eof_ && end_ > begin_)) {
      const std::size_t length =
          nl != nullptr ? static_cast<std::size_t>(nl - start) : end_ - begin_;
      line = std::string_view(start, length);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      begin_ += nl != nullptr ? length + 1 : length;
      ++line_;
      return true;
    }
    if (eof_) return false;
    // Keep the partial line, make room (a line longer than the buffer doubles it), read more.
    if (begin_ > 0) {
      std::memmove(buffer_.data(), start, end_ - begin_);
      end_ -= begin_;
      begin_ = 0;
    }
    if (end_ == buffer_.size()) buffer_.resize(buffer_.size() * 2);
    ssize_t got = 0;
    do {
      got = ::read(fd_, buffer_.data() + end_, buffer_.size() - end_);
    } while (got < 0 && errno == EINTR);
    if (got < 0) {
      throw InputError(file_, fmt::format("cannot read the file: {}", std::strerror(errno)));
    }
    if (got == 0) eof_ = true;
    end_ += static_cast<std::size_t>(got);
    read_bytes_ += static_cast<std::uint64_t>(got);
  }
}

// A field is trimmed only when it starts or ends with a blank (what most writers never write),
// so that a row costs little more than finding its commas (memchr: a byte loop is slower).
void CsvReader::split(std::string_view line) {
  fields_.clear();
  const char* p = line.data();
  const char* const end = p + line.size();
  for (;;) {
    const char* const start = p;
    const auto* comma =
        static_cast<const char*>(std::memchr(p, ',', static_cast<std::size_t>(end - p)));
    p = comma != nullptr ? comma : end;
    std::string_view f(start, static_cast<std::size_t>(p - start));
    if (!f.empty() && (blank(f.front()) || blank(f.back()))) f = trim(f);
    if (options_.unquote && f.size() >= 2 && f.front() == '"' && f.back() == '"') {
      f = trim(f.substr(1, f.size() - 2));
    }
    fields_.push_back(f);
    if (p == end) break;
    ++p;
  }
}

bool CsvReader::next() {
  std::string_view line;
  while (read_line(line)) {
    if (line.empty() || (blank(line.front()) && trim(line).empty())) {
      if (!options_.blank_lines_anywhere && blank_line_ == 0) blank_line_ = line_;
      continue;
    }
    if (blank_line_ != 0) {
      throw InputError(fmt::format("{}:{}", file_, blank_line_), "empty line before more data");
    }
    split(line);
    if (fields_.size() != columns_.size()) {
      throw InputError(where(),
                       fmt::format("expected {} columns, got {}", columns_.size(), fields_.size()));
    }
    return true;
  }
  return false;
}

double CsvReader::number(std::size_t i) const {
  const std::string_view t = fields_[i];
  if (const auto v = parse_csv_number(t)) return *v;
  // Say why: a value that parses but is not finite (nan, inf) reads differently from junk and
  // from a value beyond a double's range (std::from_chars tells these apart; fast_float gives
  // an infinity for the last).
  const std::string_view u = drop_plus(t);
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(u.data(), u.data() + u.size(), v);
  const bool non_finite = !u.empty() && ec == std::errc() && ptr == u.data() + u.size();
  throw InputError(where(), fmt::format("column {}: '{}' is not a {}number", columns_[i], t,
                                        non_finite ? "finite " : ""));
}

std::int64_t CsvReader::integer(std::size_t i) const {
  const std::string_view t = drop_plus(fields_[i]);
  std::int64_t v = 0;
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (t.empty() || ec != std::errc() || ptr != t.data() + t.size()) {
    throw InputError(where(),
                     fmt::format("column {}: '{}' is not an integer", columns_[i], fields_[i]));
  }
  return v;
}

}  // namespace calstand::core

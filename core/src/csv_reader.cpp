#include "core/csv_reader.hpp"

#include <fast_float/fast_float.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <set>
#include <thread>

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

CsvReader::CsvReader(const CsvReader& whole, std::uint64_t from, std::uint64_t to)
    : file_(whole.file_),
      options_(whole.options_),
      header_(whole.header_),
      columns_(whole.columns_) {
  fd_ = ::open(file_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw InputError(file_, "cannot open the file");
  buffer_.resize(options_.block_bytes);
  // Start one byte early and drop through the first line end: the line that starts at `from`
  // is this reader's when the byte before it ends a line, else it is the previous reader's.
  start_ = from - 1;
  if (::lseek(fd_, static_cast<off_t>(start_), SEEK_SET) < 0) {
    throw InputError(file_, fmt::format("cannot read the file: {}", std::strerror(errno)));
  }
  std::string_view partial;
  read_line(partial);
  line_ = 0;
  first_line_at_ = position();
  stop_ = to;
}

std::size_t CsvReader::lines_before() const {
  if (first_line_at_ == 0) return 0;
  if (!lines_before_) {
    // The line ends before this reader's first line (which starts just after one).
    std::vector<char> block(std::size_t{1} << 20);
    std::size_t lines = 0;
    for (std::uint64_t at = 0; at < first_line_at_;) {
      const auto want =
          static_cast<std::size_t>(std::min<std::uint64_t>(block.size(), first_line_at_ - at));
      const ssize_t got = ::pread(fd_, block.data(), want, static_cast<off_t>(at));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) break;  // the file shrank under us: count what is there
      lines += static_cast<std::size_t>(std::count(block.data(), block.data() + got, '\n'));
      at += static_cast<std::uint64_t>(got);
    }
    lines_before_ = lines;
  }
  return *lines_before_;
}

std::string CsvReader::where_at(std::size_t line) const {
  return fmt::format("{}:{}", file_, lines_before() + line);
}

std::string CsvReader::where() const { return where_at(line_); }

// The next line without its line end (LF or CR LF), or false at the end of the file. The view
// points into buffer_ and lives until the next call.
bool CsvReader::read_line(std::string_view& line) {
  if (position() >= stop_) return false;
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
std::string_view CsvReader::clean(std::string_view f) const {
  if (!f.empty() && (blank(f.front()) || blank(f.back()))) f = trim(f);
  if (options_.unquote && f.size() >= 2 && f.front() == '"' && f.back() == '"') {
    f = trim(f.substr(1, f.size() - 2));
  }
  return f;
}

void CsvReader::split(std::string_view line) {
  fields_.clear();
  const char* p = line.data();
  const char* const end = p + line.size();
  for (;;) {
    const char* const start = p;
    const auto* comma =
        static_cast<const char*>(std::memchr(p, ',', static_cast<std::size_t>(end - p)));
    p = comma != nullptr ? comma : end;
    fields_.push_back(clean(std::string_view(start, static_cast<std::size_t>(p - start))));
    if (p == end) break;
    ++p;
  }
}

bool CsvReader::next_data_line(std::string_view& line) {
  while (read_line(line)) {
    if (line.empty() || (blank(line.front()) && trim(line).empty())) {
      if (!options_.blank_lines_anywhere && blank_line_ == 0) blank_line_ = line_;
      continue;
    }
    saw_data_ = true;
    if (blank_line_ != 0) throw InputError(where_at(blank_line_), "empty line before more data");
    return true;
  }
  return false;
}

bool CsvReader::next() {
  std::string_view line;
  if (!next_data_line(line)) return false;
  split(line);
  if (fields_.size() != columns_.size()) {
    throw InputError(where(),
                     fmt::format("expected {} columns, got {}", columns_.size(), fields_.size()));
  }
  return true;
}

bool CsvReader::next_number(std::size_t i, double& value) {
  std::string_view line;
  if (!next_data_line(line)) return false;
  // Field i's bounds, then the commas after it: the field count without the other fields.
  const char* p = line.data();
  const char* const end = p + line.size();
  std::size_t fields = 1;
  for (; fields <= i; ++fields) {
    const auto* comma =
        static_cast<const char*>(std::memchr(p, ',', static_cast<std::size_t>(end - p)));
    if (comma == nullptr) break;
    p = comma + 1;
  }
  const char* field_end = end;
  if (fields == i + 1) {
    const auto* comma =
        static_cast<const char*>(std::memchr(p, ',', static_cast<std::size_t>(end - p)));
    if (comma != nullptr) field_end = comma;
    // The rest of the commas eight bytes at a time (a byte loop or a memchr per comma costs
    // more than the rest of the row): a byte of x is zero where the text has a comma, and t's
    // top bit of a byte is clear exactly where that byte of x is zero.
    const char* q = field_end;
    constexpr std::uint64_t kOnes = 0x0101010101010101ULL;
    constexpr std::uint64_t kLow7 = 0x7f7f7f7f7f7f7f7fULL;
    for (; end - q >= 8; q += 8) {
      std::uint64_t w = 0;
      std::memcpy(&w, q, 8);
      const std::uint64_t x = w ^ (kOnes * ',');
      const std::uint64_t t = ((x & kLow7) + kLow7) | x;
      // One bit per comma at the bottom of its byte, summed into the top byte by the multiply
      // (std::popcount is a library call without -mpopcnt).
      fields += static_cast<std::size_t>((((~t & ~kLow7) >> 7) * kOnes) >> 56);
    }
    for (; q < end; ++q) fields += *q == ',' ? 1 : 0;
  }
  if (fields != columns_.size()) {
    throw InputError(where(), fmt::format("expected {} columns, got {}", columns_.size(), fields));
  }
  const std::string_view f = clean(std::string_view(p, static_cast<std::size_t>(field_end - p)));
  const auto v = parse_csv_number(f);
  if (!v) refuse_number(i, f);
  value = *v;
  return true;
}

double CsvReader::number(std::size_t i) const {
  const std::string_view t = fields_[i];
  if (const auto v = parse_csv_number(t)) return *v;
  refuse_number(i, t);
}

void CsvReader::refuse_number(std::size_t i, std::string_view t) const {
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

CsvReader::Rest CsvReader::rest_of_file(unsigned threads) const {
  struct stat st {};
  if (::fstat(fd_, &st) != 0) {
    throw InputError(file_, fmt::format("cannot read the file: {}", std::strerror(errno)));
  }
  Rest rest;
  rest.from = position();
  rest.size = static_cast<std::uint64_t>(st.st_size);
  const unsigned cores = std::max(1U, std::thread::hardware_concurrency());
  rest.parts = std::max(1U, std::min(threads, cores));
  if (eof_ || rest.size <= rest.from || rest.size - rest.from < options_.parallel_min_bytes) {
    rest.parts = 1;
  }
  return rest;
}

std::vector<double> CsvReader::remaining_numbers(std::size_t i, unsigned threads) {
  std::vector<double> values;
  const Rest unread = rest_of_file(threads);
  const std::uint64_t from = unread.from, size = unread.size;
  const unsigned parts = unread.parts;
  if (parts == 1) {
    double v = 0.0;
    while (next_number(i, v)) values.push_back(v);
    return values;
  }
  // Part k reads the lines that start in [bounds[k], bounds[k + 1]); part 0 is this reader.
  std::vector<std::uint64_t> bounds;
  for (unsigned k = 0; k <= parts; ++k) bounds.push_back(from + (size - from) * k / parts);
  struct Part {
    std::unique_ptr<CsvReader> reader;
    std::vector<double> values;
    std::exception_ptr error;
  };
  std::vector<Part> rest(parts - 1);
  // Once part k has failed, parts after it need not finish: the first error in the file wins.
  std::atomic<unsigned> first_failed{parts};
  const auto read_part = [&](CsvReader& csv, std::vector<double>& out, unsigned k) {
    double v = 0.0;
    for (std::size_t row = 0; csv.next_number(i, v); ++row) {
      out.push_back(v);
      if (row % 4096 == 0 && first_failed.load(std::memory_order_relaxed) < k) return;
    }
  };
  const auto failed = [&](unsigned k) {
    unsigned seen = first_failed.load();
    while (k < seen && !first_failed.compare_exchange_weak(seen, k)) {
    }
  };
  std::vector<std::thread> workers;
  for (unsigned k = 1; k < parts; ++k) {
    workers.emplace_back([&, k] {
      Part& p = rest[k - 1];
      try {
        p.reader.reset(new CsvReader(*this, bounds[k], bounds[k + 1]));
        read_part(*p.reader, p.values, k);
      } catch (...) {
        p.error = std::current_exception();
        failed(k);
      }
    });
  }
  std::exception_ptr error;
  stop_ = bounds[1];
  try {
    read_part(*this, values, 0);
  } catch (...) {
    error = std::current_exception();
    failed(0);
  }
  for (std::thread& w : workers) w.join();
  stop_ = UINT64_MAX;
  begin_ = end_;
  eof_ = true;
  if (error) std::rethrow_exception(error);
  // A blank line that ends one part is an error once a later part has data (as next() finds
  // when it reads on), and before any error of that part: it comes first in the file.
  std::string blank;
  if (!options_.blank_lines_anywhere && blank_line_ != 0) blank = where_at(blank_line_);
  std::size_t total = values.size();
  for (const Part& p : rest) total += p.values.size();
  values.reserve(total);
  for (Part& p : rest) {
    if (!blank.empty() && p.reader && p.reader->saw_data_) {
      throw InputError(blank, "empty line before more data");
    }
    if (p.error) std::rethrow_exception(p.error);
    if (blank.empty() && !options_.blank_lines_anywhere && p.reader->blank_line_ != 0) {
      blank = p.reader->where_at(p.reader->blank_line_);
    }
    values.insert(values.end(), p.values.begin(), p.values.end());
  }
  return values;
}

void CsvReader::for_each_number_block(std::size_t i,
                                      const std::function<void(std::span<const double>)>& block,
                                      std::size_t block_rows, unsigned threads) {
  block_rows = std::max<std::size_t>(block_rows, 1);
  const Rest unread = rest_of_file(threads);
  const std::uint64_t from = unread.from, size = unread.size;
  const unsigned parts = unread.parts;
  if (parts == 1) {
    std::vector<double> values;
    values.reserve(block_rows);
    double v = 0.0;
    bool more = true;
    while (more) {
      try {
        more = next_number(i, v);
      } catch (const InputError&) {
        if (!values.empty()) block(values);  // the values before the error first
        throw;
      }
      if (more) values.push_back(v);
      if (values.size() == block_rows || (!more && !values.empty())) {
        block(values);
        values.clear();
      }
    }
    return;
  }
  // Range k is [from + k range, from + (k + 1) range), thread t parses k = t, t + parts, ...
  // into slot k % window once range k - window has been given out.
  const std::uint64_t range = std::max<std::uint64_t>(options_.range_bytes, 1);
  const std::uint64_t ranges = (size - from + range - 1) / range;
  const std::size_t window = 2 * static_cast<std::size_t>(parts);
  struct Range {
    std::uint64_t index = UINT64_MAX;  // the range in this slot; UINT64_MAX: none
    std::vector<double> values;
    std::exception_ptr error;
    std::string blank;  // `FILE:LINE` of its first blank line, when they may only end the file
    bool saw_data = false;
  };
  std::vector<Range> slots(window);
  std::mutex mutex;
  std::condition_variable changed;
  std::uint64_t consumed = 0;  // ranges given out
  bool stop = false;
  const auto parse = [&](unsigned t) {
    for (std::uint64_t k = t; k < ranges; k += parts) {
      {
        std::unique_lock lock(mutex);
        changed.wait(lock, [&] { return stop || k < consumed + window; });
        if (stop) return;
      }
      Range r;
      r.index = k;
      std::unique_ptr<CsvReader> csv;
      try {
        csv.reset(new CsvReader(*this, from + k * range, std::min(size, from + (k + 1) * range)));
        double v = 0.0;
        while (csv->next_number(i, v)) r.values.push_back(v);
        if (!options_.blank_lines_anywhere && csv->blank_line_ != 0) {
          r.blank = csv->where_at(csv->blank_line_);
        }
      } catch (...) {
        r.error = std::current_exception();
      }
      r.saw_data = csv && csv->saw_data_;
      std::lock_guard lock(mutex);
      slots[k % window] = std::move(r);
      changed.notify_all();
    }
  };
  std::vector<std::thread> workers;
  const auto finish = [&] {
    {
      std::lock_guard lock(mutex);
      stop = true;
    }
    changed.notify_all();
    for (std::thread& w : workers) w.join();
    begin_ = end_;
    eof_ = true;
  };
  // A blank line is an error once more data follow (as next() finds when it reads on); this
  // reader's own comes first in the file.
  std::string blank;
  if (!options_.blank_lines_anywhere && blank_line_ != 0) blank = where_at(blank_line_);
  try {
    for (unsigned t = 0; t < parts; ++t) workers.emplace_back(parse, t);
    for (std::uint64_t k = 0; k < ranges; ++k) {
      Range r;
      {
        std::unique_lock lock(mutex);
        changed.wait(lock, [&] { return slots[k % window].index == k; });
        r = std::move(slots[k % window]);
        slots[k % window].index = UINT64_MAX;
        consumed = k + 1;
      }
      changed.notify_all();
      if (!blank.empty() && r.saw_data) throw InputError(blank, "empty line before more data");
      for (std::size_t at = 0; at < r.values.size(); at += block_rows) {
        block(std::span<const double>(r.values).subspan(
            at, std::min(block_rows, r.values.size() - at)));
      }
      if (r.error) std::rethrow_exception(r.error);
      if (blank.empty()) blank = r.blank;
    }
  } catch (...) {
    finish();
    throw;
  }
  finish();
}

}  // namespace calstand::core

#pragma once
// Reading numeric CSV files fast: the one reader of `calstand import` (samples.csv) and
// `calstand allan --csv`.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::core {

/// How a CsvReader treats what varies between CSV writers.
struct CsvOptions {
  /// Blank lines (nothing but spaces, tabs or a CR) are skipped wherever they are (true), or
  /// allowed only at the end of the file (false: one followed by more data is an error naming
  /// the blank line, which is where a truncated concatenation of two files shows).
  bool blank_lines_anywhere = false;
  /// Fields written in double quotes ("1.5", a header "gx") are read without them. There is no
  /// escaping: a quoted field holding a comma is two fields.
  bool unquote = false;
  /// Bytes read from the file at a time; a longer line grows the buffer to hold it.
  std::size_t block_bytes = std::size_t{1} << 22;
  /// CsvReader::remaining_numbers reads a rest of the file shorter than this on one thread
  /// (starting a thread and splitting pays from a few megabytes on).
  std::uint64_t parallel_min_bytes = std::uint64_t{8} << 20;
  /// CsvReader::for_each_number_block parses the file in byte ranges of this size, one per
  /// thread at a time (the memory it holds is a few of them, whatever the file's length).
  std::uint64_t range_bytes = std::uint64_t{4} << 20;
};

/// A CSV file with a header line, read front to back in large blocks (read(2) into one
/// buffer, no per-line allocation), its numbers parsed with fast_float (Debian's
/// libfast-float-dev, header only).
///
/// Lines end with LF or CR LF; the last may lack its line end; a UTF-8 byte order mark before
/// the header is dropped. Fields are separated by commas and trimmed of spaces and tabs. Every
/// data row must have exactly as many fields as the header (a missing or an extra field is an
/// error naming the line). Numbers: an optional sign ('+' too), digits with an optional
/// fraction and exponent (`1`, `-0.5`, `.5`, `2.`, `6.02e23`, `1E-05`); `nan`, `inf`, hex and
/// anything trailing are refused, as is a value beyond the range of a double.
///
/// Why fast_float rather than std::from_chars: both round correctly and identically (GCC 12's
/// libstdc++ implements from_chars for double with the same Eisel-Lemire algorithm), but the
/// header-only fast_float inlines into the field loop where from_chars is a call into the
/// shared library: 35 against 26 million numbers per second on the same fields in
/// bench/csv_read_bench.cpp (BM_ParseNumbers*), about a sixth of an import's reading time.
/// std::from_chars still classifies a refused field for its message.
///
/// Errors are core::InputError: where() is the file (cannot open, empty) or `FILE:LINE`, and
/// the message names the column (`column gx: 'abc' is not a number`).
class CsvReader {
 public:
  /// Opens `path` and reads its header. Throws InputError when the file cannot be opened or is
  /// empty.
  explicit CsvReader(const std::filesystem::path& path, CsvOptions options = {});
  ~CsvReader();
  CsvReader(const CsvReader&) = delete;
  CsvReader& operator=(const CsvReader&) = delete;

  /// The file name as given, as it appears in messages.
  const std::string& file() const { return file_; }
  /// The header's column names, trimmed (and unquoted with CsvOptions::unquote).
  const std::vector<std::string>& columns() const { return columns_; }
  /// The header line as written (trimmed, byte order mark dropped), for messages.
  const std::string& header() const { return header_; }
  /// Index of column `name` (the first, when named twice), none when the header lacks it.
  std::optional<std::size_t> column(std::string_view name) const;
  /// Throws InputError (`FILE:1`) naming the first column the header names twice.
  void require_unique_columns() const;

  /// Reads the next data row (blank lines as CsvOptions says); false at the end of the file.
  /// Throws InputError for a row whose field count differs from the header's, or a misplaced
  /// blank line. The fields of the previous row are invalid afterwards.
  bool next();

  /// 1-based line number of the current row (the header is line 1).
  std::size_t line() const { return lines_before() + line_; }
  /// `FILE:LINE` of the current row.
  std::string where() const;
  /// Bytes of the file consumed so far (through the current row), for a progress display.
  std::uint64_t offset() const { return position(); }
  /// Field `i` of the current row, trimmed. Precondition: i < columns().size().
  std::string_view field(std::size_t i) const { return fields_[i]; }
  /// Field `i` as a finite number. Throws InputError naming the line and column otherwise.
  double number(std::size_t i) const;
  /// Field `i` as a whole number (optional sign, digits). Throws InputError naming the line and
  /// column otherwise.
  std::int64_t integer(std::size_t i) const;

  /// Field `i` of every remaining row as number() reads it, in file order, the rest of the file
  /// read by up to `threads` threads (at most one per core): byte ranges split at line
  /// boundaries, each read by a reader of its own (its own file descriptor and buffer), the
  /// first on the calling thread. The same values and the same error (the first in the file:
  /// `FILE:LINE: column gx: ...`, a field count, a misplaced blank line) as next() and
  /// number(i) to the end of the file would give; next() returns false afterwards. Why: reading
  /// is most of `calstand allan --csv` on a long record (issue 32), and lines split cleanly.
  std::vector<double> remaining_numbers(std::size_t i, unsigned threads = 2);

  /// remaining_numbers() in constant memory: field `i` of every remaining row, the same values
  /// in file order, given to `block` (on the calling thread) in spans of at most `block_rows`
  /// values while up to `threads` threads (at most one per core) parse ahead. The rest of the
  /// file is cut into byte ranges (CsvOptions::range_bytes, 4 MB) split at line boundaries, parsed
  /// in turn by the threads (each range by a reader of its own), at most two ranges per thread
  /// ahead of `block`: memory does not grow with the file. The same error as remaining_numbers()
  /// (the first in the file), thrown once the values before it have been given to `block`; an
  /// exception from `block` stops the reading and is rethrown. next() returns false afterwards.
  /// Why: a day at 1 kHz (86 million rows) read for a streamed deviation (solver::DeviationStream).
  void for_each_number_block(std::size_t i,
                             const std::function<void(std::span<const double>)>& block,
                             std::size_t block_rows = std::size_t{1} << 16U, unsigned threads = 2);

 private:
  /// A reader of the data rows of `whole`'s file whose line starts at a byte in [from, to),
  /// with `whole`'s header and options; its line numbers are counted when a message needs them.
  CsvReader(const CsvReader& whole, std::uint64_t from, std::uint64_t to);
  bool read_line(std::string_view& line);
  /// The rest of the file from the next line on, as the parallel readers split it.
  struct Rest {
    std::uint64_t from = 0;  ///< file offset of the next line
    std::uint64_t size = 0;  ///< the file's size [bytes]
    unsigned parts = 1;      ///< threads to read it on; 1: read it here, serially
  };
  /// The rest, in at most `threads` parts (the cores permitting): one part when the rest is
  /// smaller than options.parallel_min_bytes or this reader is at the end.
  Rest rest_of_file(unsigned threads) const;
  /// The next line that is not blank (blank ones handled as next() says), false at the end.
  bool next_data_line(std::string_view& line);
  void split(std::string_view line);
  /// A raw field as split() keeps it: trimmed when it starts or ends with a blank, unquoted.
  std::string_view clean(std::string_view field) const;
  /// The next row's field `i` as number(i) reads it, its field count checked as next() does,
  /// without splitting the other fields (remaining_numbers); false at the end of the file.
  bool next_number(std::size_t i, double& value);
  [[noreturn]] void refuse_number(std::size_t i, std::string_view text) const;
  /// Lines of the file before this reader's first line (0 for a reader from the start): counted
  /// once, when a message needs a line number.
  std::size_t lines_before() const;
  std::string where_at(std::size_t line) const;
  /// File offset of buffer_[begin_]: where the next line starts.
  std::uint64_t position() const { return start_ + read_bytes_ - (end_ - begin_); }

  std::string file_;
  CsvOptions options_;
  int fd_ = -1;
  std::vector<char> buffer_;
  std::size_t begin_ = 0;  // first unconsumed byte of buffer_
  std::size_t end_ = 0;    // one past the last byte read into buffer_
  bool eof_ = false;
  std::uint64_t read_bytes_ = 0;  // bytes read from the file so far
  std::size_t line_ = 0;          // line number of the line read last
  std::size_t blank_line_ = 0;    // first blank line seen while blank lines are only allowed last
  bool saw_data_ = false;         // a line that is not blank was read (remaining_numbers)
  std::uint64_t start_ = 0;       // file offset of the first byte read
  std::uint64_t stop_ = UINT64_MAX;  // lines starting at or after this offset are not read
  std::uint64_t first_line_at_ = 0;  // file offset of this reader's first line
  mutable std::optional<std::size_t> lines_before_;  // see lines_before()
  std::string header_;
  std::vector<std::string> columns_;
  std::vector<std::string_view> fields_;
};

/// Parses `text` (already trimmed) as CsvReader::number() does: the value, or none when it is
/// not a finite number in the accepted syntax.
std::optional<double> parse_csv_number(std::string_view text);

}  // namespace calstand::core

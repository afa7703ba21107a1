#pragma once
// Reading numeric CSV files fast: the one reader of `calstand import` (samples.csv) and
// `calstand allan --csv`.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
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
  std::size_t line() const { return line_; }
  /// `FILE:LINE` of the current row.
  std::string where() const;
  /// Bytes of the file consumed so far (through the current row), for a progress display.
  std::uint64_t offset() const { return read_bytes_ - (end_ - begin_); }
  /// Field `i` of the current row, trimmed. Precondition: i < columns().size().
  std::string_view field(std::size_t i) const { return fields_[i]; }
  /// Field `i` as a finite number. Throws InputError naming the line and column otherwise.
  double number(std::size_t i) const;
  /// Field `i` as a whole number (optional sign, digits). Throws InputError naming the line and
  /// column otherwise.
  std::int64_t integer(std::size_t i) const;

 private:
  bool read_line(std::string_view& line);
  void split(std::string_view line);

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
  std::string header_;
  std::vector<std::string> columns_;
  std::vector<std::string_view> fields_;
};

/// Parses `text` (already trimmed) as CsvReader::number() does: the value, or none when it is
/// not a finite number in the accepted syntax.
std::optional<double> parse_csv_number(std::string_view text);

}  // namespace calstand::core

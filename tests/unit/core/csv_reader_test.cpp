// The CSV reader of `calstand import` and `calstand allan --csv`: line ends, blank lines,
// number syntax, field counts, long lines and block boundaries, and the FILE:LINE: column
// messages.
#include "core/csv_reader.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace calstand::core {
namespace {

// A file with `text` under the temp folder, removed at scope end.
class CsvFile {
 public:
  explicit CsvFile(const std::string& text) {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("calstand-csv-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) +
             ".csv");
    std::ofstream(path_, std::ios::binary) << text;
  }
  ~CsvFile() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }
  std::string name() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

// Every row's numbers, column by column.
std::vector<std::vector<double>> numbers(const CsvFile& f, CsvOptions options = {}) {
  CsvReader csv(f.path(), options);
  std::vector<std::vector<double>> out;
  while (csv.next()) {
    out.emplace_back();
    for (std::size_t i = 0; i < csv.columns().size(); ++i) out.back().push_back(csv.number(i));
  }
  return out;
}

// The InputError text of reading every number of `text`.
std::string error_of(const std::string& text, CsvOptions options = {}) {
  CsvFile f(text);
  try {
    numbers(f, options);
  } catch (const InputError& e) {
    return std::string(e.what()).replace(0, f.name().size(), "FILE");
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return "";
}

using Rows = std::vector<std::vector<double>>;

TEST(CsvReader, ReadsHeaderAndRows) {
  CsvFile f("t, gx ,gy\n0,1.5,-2\n0.01,2.5,3\n");
  CsvReader csv(f.path());
  EXPECT_EQ(csv.columns(), (std::vector<std::string>{"t", "gx", "gy"}));
  EXPECT_EQ(csv.column("gx"), 1u);
  EXPECT_FALSE(csv.column("gz"));
  ASSERT_TRUE(csv.next());
  EXPECT_EQ(csv.line(), 2u);
  EXPECT_EQ(csv.number(2), -2.0);
  ASSERT_TRUE(csv.next());
  EXPECT_EQ(csv.line(), 3u);
  EXPECT_EQ(csv.where(), f.name() + ":3");
  EXPECT_FALSE(csv.next());
}

TEST(CsvReader, CrLfAndMissingFinalLineEndAndByteOrderMark) {
  EXPECT_EQ(numbers(CsvFile("\xEF\xBB\xBFt,v\r\n1,2\r\n3,4\r\n")), (Rows{{1, 2}, {3, 4}}));
  EXPECT_EQ(numbers(CsvFile("t,v\n1,2\n3,4")), (Rows{{1, 2}, {3, 4}}));
  EXPECT_EQ(numbers(CsvFile("t,v\r\n1,2\r\n3,4")), (Rows{{1, 2}, {3, 4}}));
  CsvFile bom("\xEF\xBB\xBFt,v\n1,2\n");
  EXPECT_EQ(CsvReader(bom.path()).columns().front(), "t");
}

TEST(CsvReader, BlankLinesOnlyAtTheEndUnlessAllowed) {
  EXPECT_EQ(numbers(CsvFile("t,v\n1,2\n\n  \r\n\t\n")), (Rows{{1, 2}}));
  EXPECT_EQ(error_of("t,v\n1,2\n\n3,4\n"), "FILE:3: empty line before more data");
  CsvOptions anywhere;
  anywhere.blank_lines_anywhere = true;
  CsvFile f("t,v\n\n1,2\n \r\n3,4\n");
  EXPECT_EQ(numbers(f, anywhere), (Rows{{1, 2}, {3, 4}}));
  CsvReader csv(f.path(), anywhere);
  ASSERT_TRUE(csv.next());
  EXPECT_EQ(csv.line(), 3u);  // line numbers count the blank lines
  ASSERT_TRUE(csv.next());
  EXPECT_EQ(csv.line(), 5u);
}

TEST(CsvReader, NumberSyntax) {
  const Rows rows =
      numbers(CsvFile("a,b,c,d,e,f,g,h\n+1,-0.5,.5,2.,6.02e23,1E-05,+1.5e+3, 7 "
                      "\n-0,0.1,1e-320,1.7976931348623157e308,"
                      "4.9e-324,123456789012345678901234567890,-1e+2,0\n"));
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0], (std::vector<double>{1, -0.5, 0.5, 2, 6.02e23, 1e-5, 1500, 7}));
  EXPECT_EQ(rows[1][1], 0.1);  // correctly rounded
  EXPECT_EQ(rows[1][2], 1e-320);
  EXPECT_EQ(rows[1][3], 1.7976931348623157e308);
  EXPECT_EQ(rows[1][5], 1.2345678901234568e29);
  EXPECT_TRUE(std::signbit(rows[1][0]));
}

TEST(CsvReader, RefusesWhatIsNotAFiniteNumberNamingLineAndColumn) {
  EXPECT_EQ(error_of("t,gx\n1,2\n1,nan\n"), "FILE:3: column gx: 'nan' is not a finite number");
  EXPECT_EQ(error_of("t,gx\n1,inf\n"), "FILE:2: column gx: 'inf' is not a finite number");
  EXPECT_EQ(error_of("t,gx\n1,-Infinity\n"),
            "FILE:2: column gx: '-Infinity' is not a finite number");
  EXPECT_EQ(error_of("t,gx\n1,1e999\n"), "FILE:2: column gx: '1e999' is not a number");
  EXPECT_EQ(error_of("t,gx\n1,0x1p3\n"), "FILE:2: column gx: '0x1p3' is not a number");
  EXPECT_EQ(error_of("t,gx\n1,1.5.2\n"), "FILE:2: column gx: '1.5.2' is not a number");
  EXPECT_EQ(error_of("t,gx\n1,1e\n"), "FILE:2: column gx: '1e' is not a number");
  EXPECT_EQ(error_of("t,gx\n1,+-1\n"), "FILE:2: column gx: '+-1' is not a number");
  EXPECT_EQ(error_of("t,gx\n1,++1\n"), "FILE:2: column gx: '++1' is not a number");
  EXPECT_EQ(error_of("t,gx\n1,\n"), "FILE:2: column gx: '' is not a number");
  EXPECT_EQ(error_of("t,gx\n1,1 2\n"), "FILE:2: column gx: '1 2' is not a number");
  EXPECT_EQ(error_of("t,gx\n1,\"2\"\n"), "FILE:2: column gx: '\"2\"' is not a number");
}

TEST(CsvReader, MissingOrExtraFieldNamesTheLine) {
  EXPECT_EQ(error_of("t,gx,gy\n1,2,3\n1,2\n"), "FILE:3: expected 3 columns, got 2");
  EXPECT_EQ(error_of("t,gx,gy\n1,2,3,4\n"), "FILE:2: expected 3 columns, got 4");
  EXPECT_EQ(error_of("t,gx,gy\n1,2,3,\n"), "FILE:2: expected 3 columns, got 4");
}

TEST(CsvReader, Integers) {
  CsvFile f("step\n+3\n-2\n1.5\n");
  CsvReader csv(f.path());
  ASSERT_TRUE(csv.next());
  EXPECT_EQ(csv.integer(0), 3);
  ASSERT_TRUE(csv.next());
  EXPECT_EQ(csv.integer(0), -2);
  ASSERT_TRUE(csv.next());
  try {
    csv.integer(0);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), f.name() + ":4: column step: '1.5' is not an integer");
  }
}

TEST(CsvReader, QuotesOnlyWhenAsked) {
  CsvOptions unquote;
  unquote.unquote = true;
  CsvFile f("\"t\",\"rate\"\n\"1\", \"2.5\" \n");
  CsvReader csv(f.path(), unquote);
  EXPECT_EQ(csv.column("rate"), 1u);
  ASSERT_TRUE(csv.next());
  EXPECT_EQ(csv.number(1), 2.5);
}

TEST(CsvReader, VeryLongLinesAndBlockBoundaries) {
  // A 3 MB line (a header of 400,000 columns) read through 4 kB blocks: the buffer grows.
  std::string header, row;
  for (int i = 0; i < 400000; ++i) {
    header += (i ? ",c" : "c") + std::to_string(i);
    row += (i ? "," : "") + std::to_string(i % 97) + ".25";
  }
  CsvOptions small;
  small.block_bytes = 4096;
  CsvFile f(header + "\n" + row + "\n" + row);
  CsvReader csv(f.path(), small);
  EXPECT_EQ(csv.columns().size(), 400000u);
  ASSERT_TRUE(csv.next());
  EXPECT_EQ(csv.number(399999), 399999 % 97 + 0.25);
  ASSERT_TRUE(csv.next());
  EXPECT_EQ(csv.number(12345), 12345 % 97 + 0.25);
  EXPECT_FALSE(csv.next());

  // Many short rows straddling tiny blocks: every value and line number survives.
  std::string text = "t,v\r\n";
  for (int i = 0; i < 5000; ++i) text += std::to_string(i) + "," + std::to_string(i * 0.5) + "\r\n";
  CsvOptions tiny;
  tiny.block_bytes = 64;
  CsvFile g(text);
  CsvReader rows(g.path(), tiny);
  int n = 0;
  while (rows.next()) {
    ASSERT_EQ(rows.number(0), n);
    ASSERT_EQ(rows.number(1), n * 0.5);
    ASSERT_EQ(rows.line(), static_cast<std::size_t>(n) + 2);
    ++n;
  }
  EXPECT_EQ(n, 5000);
}

TEST(CsvReader, FileErrors) {
  try {
    CsvReader("/nonexistent/calstand.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/calstand.csv: cannot open the file");
  }
  CsvFile empty("");
  EXPECT_THROW(CsvReader{empty.path()}, InputError);
  CsvFile header_only("t,v\n");
  CsvReader csv(header_only.path());
  EXPECT_FALSE(csv.next());
  CsvFile twice("t,v,t\n1,2,3\n");
  try {
    CsvReader(twice.path()).require_unique_columns();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), twice.name() + ":1: column 't' appears twice in the header");
  }
}

// --- remaining_numbers: the rest of the file on several threads ----------------------------

// A static IMU record as writers print it: a gyro axis of white noise on a bias random walk (a
// low-grade MEMS gyro at 400 Hz: 0.01 deg/s/sqrt(Hz) angle random walk, 1e-4 deg/s/sqrt(s) rate
// random walk) and an accelerometer axis sharing the temperature drift; %.9g, CR LF and a '+'
// now and then, as C writers do.
std::string imu_csv(int rows, std::uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const double rate_hz = 400.0;
  double bias = 0.02, drift = 0.0;
  std::string text = "t,gx,az\r\n";
  for (int i = 0; i < rows; ++i) {
    bias += 1e-4 / std::sqrt(rate_hz) * unit(rng);
    drift += 1e-5 * unit(rng);
    const double gx = bias + drift + 0.01 * std::sqrt(rate_hz) * unit(rng);
    const double az = 9.80665 + 50.0 * drift + 2e-3 * unit(rng);
    text += i % 7 == 3 ? fmt::format("{:.9g},{:+.9g},{:.9g}\r\n", i / rate_hz, gx, az)
                       : fmt::format("{:.9g},{:.9g},{:.9g}\r\n", i / rate_hz, gx, az);
  }
  return text;
}

// Column `i` read row by row (next() and number(i)): the peer remaining_numbers must equal.
std::vector<double> column_by_rows(const CsvFile& f, std::size_t i, CsvOptions options) {
  CsvReader csv(f.path(), options);
  std::vector<double> out;
  while (csv.next()) out.push_back(csv.number(i));
  return out;
}

// The InputError text of remaining_numbers (FILE for the file name), "" when none.
std::string parallel_error(const CsvFile& f, CsvOptions options, unsigned threads) {
  try {
    CsvReader csv(f.path(), options);
    csv.remaining_numbers(1, threads);
  } catch (const InputError& e) {
    return std::string(e.what()).replace(0, f.name().size(), "FILE");
  }
  return "";
}

std::string sequential_error(const CsvFile& f, CsvOptions options) {
  try {
    column_by_rows(f, 1, options);
  } catch (const InputError& e) {
    return std::string(e.what()).replace(0, f.name().size(), "FILE");
  }
  return "";
}

TEST(CsvReader, RemainingNumbersOnThreadsEqualReadingRowByRow) {
  CsvFile f(imu_csv(20000, 11));
  for (const std::size_t block : {std::size_t{64}, std::size_t{4096}, std::size_t{1} << 22}) {
    CsvOptions options;
    options.block_bytes = block;
    options.parallel_min_bytes = 0;
    for (const std::size_t column : {std::size_t{1}, std::size_t{2}}) {
      const std::vector<double> expected = column_by_rows(f, column, options);
      ASSERT_EQ(expected.size(), 20000u);
      for (const unsigned threads : {1U, 2U, 3U}) {
        CsvReader csv(f.path(), options);
        const std::vector<double> got = csv.remaining_numbers(column, threads);
        // Exactly: the same parse of the same text, in file order.
        ASSERT_EQ(got, expected) << "block " << block << " column " << column << " threads "
                                 << threads;
        EXPECT_FALSE(csv.next());
      }
    }
  }
  // Quoted and padded fields, as `calstand allan --csv` reads them (unquote, blank lines).
  std::string quoted = "\"t\", \"gx\" ,az\n";
  for (int i = 0; i < 3000; ++i) {
    quoted += i % 5 == 0 ? fmt::format("{}, \"{}\" ,1\n\n", i, i * 0.125)
                         : fmt::format("{},{} ,1\n", i, i * 0.125);
  }
  CsvFile q(quoted);
  CsvOptions cli;
  cli.unquote = true;
  cli.blank_lines_anywhere = true;
  cli.parallel_min_bytes = 0;
  CsvReader quoted_csv(q.path(), cli);
  const std::vector<double> quoted_values = quoted_csv.remaining_numbers(1, 2);
  EXPECT_EQ(quoted_values, column_by_rows(q, 1, cli));
  ASSERT_EQ(quoted_values.size(), 3000u);
  EXPECT_EQ(quoted_values[2999], 2999 * 0.125);
  // After rows read one by one, the rest only; a file with no data row gives none.
  CsvOptions options;
  options.parallel_min_bytes = 0;
  CsvReader csv(f.path(), options);
  ASSERT_TRUE(csv.next());
  ASSERT_TRUE(csv.next());
  const std::vector<double> rest = csv.remaining_numbers(1, 2);
  const std::vector<double> all = column_by_rows(f, 1, options);
  EXPECT_EQ(rest, std::vector<double>(all.begin() + 2, all.end()));
  CsvFile header_only("t,gx\n");
  EXPECT_TRUE(CsvReader(header_only.path(), options).remaining_numbers(1, 2).empty());
}

// A bad row anywhere, including either side of where the file is split: the same message,
// naming the same FILE:LINE, as reading row by row.
TEST(CsvReader, RemainingNumbersNameTheFirstBadLineWhereverTheSplitFalls) {
  const int rows = 120;
  std::vector<std::string> lines;
  for (int i = 0; i < rows; ++i) lines.push_back(fmt::format("{},{:.6f}", i, 0.001 * i * i));
  CsvOptions options;
  options.parallel_min_bytes = 0;
  options.block_bytes = 256;
  const auto file_with = [&](int at, const std::string& bad, int second_at = -1) {
    std::string text = "t,gx\n";
    for (int i = 0; i < rows; ++i) {
      text += (i == at || i == second_at ? bad : lines[static_cast<std::size_t>(i)]) + "\n";
    }
    return text;
  };
  for (int at = 0; at < rows; ++at) {
    for (const std::string bad : {"1,abc", "1,2,3", "1,nan", "7", "1,1e999"}) {
      CsvFile f(file_with(at, bad));
      const std::string expected = sequential_error(f, options);
      ASSERT_EQ(expected.rfind(fmt::format("FILE:{}: ", at + 2), 0), 0u) << expected;
      for (const unsigned threads : {2U, 3U}) {
        EXPECT_EQ(parallel_error(f, options, threads), expected) << "row " << at;
      }
    }
    // Two bad rows: the first in the file is named, whichever part finds its own first.
    CsvFile two(file_with(at, "1,x", rows - 1 - at));
    EXPECT_EQ(parallel_error(two, options, 2), sequential_error(two, options)) << "row " << at;
  }
}

TEST(CsvReader, RemainingNumbersFindABlankLineBeforeMoreDataAcrossTheSplit) {
  CsvOptions options;
  options.parallel_min_bytes = 0;
  options.block_bytes = 128;
  for (int at = 0; at < 80; ++at) {
    std::string text = "t,gx\n";
    for (int i = 0; i < 80; ++i) text += i == at ? "\n" : fmt::format("{},{}\n", i, i * 0.25);
    CsvFile f(text);
    const std::string expected = sequential_error(f, options);
    const std::string want =
        at == 79 ? "" : fmt::format("FILE:{}: empty line before more data", at + 2);
    ASSERT_EQ(expected, want);
    EXPECT_EQ(parallel_error(f, options, 2), expected) << "blank line " << at + 2;
    EXPECT_EQ(parallel_error(f, options, 3), expected) << "blank line " << at + 2;
    CsvOptions anywhere = options;
    anywhere.blank_lines_anywhere = true;
    CsvReader csv(f.path(), anywhere);
    EXPECT_EQ(csv.remaining_numbers(1, 2), column_by_rows(f, 1, anywhere));
  }
}

// for_each_number_block's values, concatenated.
std::vector<double> blocked(const CsvFile& f, std::size_t column, CsvOptions options,
                            std::size_t rows, unsigned threads) {
  CsvReader csv(f.path(), options);
  std::vector<double> out;
  csv.for_each_number_block(
      column,
      [&](std::span<const double> b) {
        EXPECT_LE(b.size(), rows);
        EXPECT_FALSE(b.empty());
        out.insert(out.end(), b.begin(), b.end());
      },
      rows, threads);
  EXPECT_FALSE(csv.next());
  return out;
}

// The InputError text of for_each_number_block (FILE for the file name), "" when none, and
// the values it gave before the error.
std::string blocked_error(const CsvFile& f, CsvOptions options, unsigned threads,
                          std::size_t* given = nullptr) {
  std::size_t n = 0;
  try {
    CsvReader csv(f.path(), options);
    csv.for_each_number_block(
        1, [&](std::span<const double> b) { n += b.size(); }, 3, threads);
  } catch (const InputError& e) {
    if (given) *given = n;
    return std::string(e.what()).replace(0, f.name().size(), "FILE");
  }
  if (given) *given = n;
  return "";
}

TEST(CsvReader, NumberBlocksEqualReadingRowByRow) {
  CsvFile f(imu_csv(20000, 13));
  for (const std::uint64_t range :
       {std::uint64_t{37}, std::uint64_t{5000}, std::uint64_t{4} << 20}) {
    CsvOptions options;
    options.block_bytes = 4096;
    options.parallel_min_bytes = 0;
    options.range_bytes = range;
    const std::vector<double> expected = column_by_rows(f, 1, options);
    ASSERT_EQ(expected.size(), 20000u);
    for (const std::size_t rows : {std::size_t{1}, std::size_t{7}, std::size_t{65536}}) {
      for (const unsigned threads : {1U, 2U, 3U}) {
        EXPECT_EQ(blocked(f, 1, options, rows, threads), expected)
            << "range " << range << " rows " << rows << " threads " << threads;
      }
    }
  }
  CsvFile header_only("t,gx\n");
  CsvOptions options;
  options.parallel_min_bytes = 0;
  EXPECT_TRUE(blocked(header_only, 1, options, 10, 2).empty());
}

// The same message as reading row by row, wherever the bad row falls against the ranges, with
// every value before it given first.
TEST(CsvReader, NumberBlocksNameTheFirstBadLineAndBlankLines) {
  const int rows = 120;
  CsvOptions options;
  options.parallel_min_bytes = 0;
  options.block_bytes = 256;
  options.range_bytes = 61;
  for (int at = 0; at < rows; ++at) {
    for (const std::string bad : {"1,abc", "1,2,3", "1,nan", "7", "1,1e999", ""}) {
      std::string text = "t,gx\n";
      for (int i = 0; i < rows; ++i) {
        text += (i == at ? bad : fmt::format("{},{:.6f}", i, 0.001 * i * i)) + "\n";
      }
      CsvFile f(text);
      const std::string expected = sequential_error(f, options);
      if (!(bad.empty() && at == rows - 1)) {
        ASSERT_FALSE(expected.empty()) << bad << " " << at;
      }
      for (const unsigned threads : {1U, 2U}) {
        std::size_t given = 0;
        EXPECT_EQ(blocked_error(f, options, threads, &given), expected)
            << "row " << at << " '" << bad << "' threads " << threads;
        if (!expected.empty()) {
          EXPECT_EQ(given, static_cast<std::size_t>(at));
        }
      }
    }
  }
}

TEST(ParseCsvNumber, SameRulesAsTheReader) {
  EXPECT_EQ(parse_csv_number("+2.5"), 2.5);
  EXPECT_EQ(parse_csv_number("-1e3"), -1000.0);
  EXPECT_FALSE(parse_csv_number("nan"));
  EXPECT_FALSE(parse_csv_number("+"));
  EXPECT_FALSE(parse_csv_number(""));
}

}  // namespace
}  // namespace calstand::core

// A CSV column streamed into a DeviationStream (noise/record_stream) against the same column
// read whole: the same curve and the same identified noise model, and the reader's messages.
#include "noise/record_stream.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "composite_records.hpp"
#include "core/csv_reader.hpp"
#include "core/error.hpp"
#include "noise/allan.hpp"
#include "noise/composite_noise.hpp"

namespace calstand::solver {
namespace {

constexpr double kCsvRateHz = testing::kCompositeRateHz;  // Hz

// A CSV file under the temp folder, removed at scope end.
class RecordFile {
 public:
  explicit RecordFile(const std::string& text) {
    path_ = (std::filesystem::temp_directory_path() /
             fmt::format("calstand-record-stream-{}.csv", ::getpid()))
                .string();
    std::ofstream(path_, std::ios::binary) << text;
  }
  ~RecordFile() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::vector<double> column_of(const std::string& path) {
  core::CsvOptions options;
  options.blank_lines_anywhere = true;
  options.unquote = true;
  core::CsvReader csv(path, options);
  return csv.remaining_numbers(*csv.column("gx"), 2);
}

// 60,000 rows (below the exact budget), about 2 MB: the block reader's two threads and ranges
// (parallel_min_bytes is 8 MB, so the small file is read on one thread: see csv_reader_test for
// the split itself).
TEST(RecordStream, CsvColumnGivesTheInMemoryCurveAndModel) {
  using K = NoiseKind;
  const std::vector<double> y = testing::simulate_composite(
      {{K::kWhite, 0.005}, {K::kGaussMarkov, 0.004, 2.0}, {K::kRandomWalk, 5e-4}}, 60000, 41u);
  std::string text = "t,gx\n";
  for (std::size_t i = 0; i < y.size(); ++i) {
    text += fmt::format("{},{:.17g}\n", static_cast<double>(i) / kCsvRateHz, y[i]);
  }
  RecordFile f(text);
  const std::vector<double> whole = column_of(f.path());
  ASSERT_EQ(whole, y);  // 17 digits: the same doubles

  DeviationStream s({AllanKind::kAllan});
  stream_csv_column(f.path(), "gx", s);
  EXPECT_EQ(s.samples(), y.size());
  const AllanResult want = allan(whole, kCsvRateHz);
  const AllanResult got = s.result(kCsvRateHz, {});
  ASSERT_EQ(got.points.size(), want.points.size());
  for (std::size_t k = 0; k < want.points.size(); ++k) {
    EXPECT_NEAR(got.points[k].deviation / want.points[k].deviation, 1.0, 1e-12);
  }
  const NoiseModel model_want = identify_noise_model(whole, kCsvRateHz);
  const NoiseModel model_got = identify_noise_model(s.moments(kCsvRateHz));
  ASSERT_EQ(model_got.terms.size(), model_want.terms.size());
  for (std::size_t i = 0; i < model_want.terms.size(); ++i) {
    EXPECT_EQ(model_got.terms[i].kind, model_want.terms[i].kind);
    EXPECT_NEAR(model_got.terms[i].value / model_want.terms[i].value, 1.0, 1e-6);
    EXPECT_NEAR(model_got.terms[i].value_lo / model_want.terms[i].value_lo, 1.0, 1e-6);
  }
}

TEST(RecordStream, CsvErrorsNameTheFileLineAndColumn) {
  {
    RecordFile f("t,gx\n0,1\n0.01,2\n0.02,oops\n");
    DeviationStream s({AllanKind::kAllan});
    try {
      stream_csv_column(f.path(), "gx", s);
      FAIL() << "a bad row was accepted";
    } catch (const core::InputError& e) {
      EXPECT_EQ(std::string(e.what()), f.path() + ":4: column gx: 'oops' is not a number");
    }
    EXPECT_EQ(s.samples(), 2u);  // the rows before it
  }
  RecordFile f("t,rate\n0,1\n");
  DeviationStream s({AllanKind::kAllan});
  try {
    stream_csv_column(f.path(), "gx", s);
    FAIL() << "a missing column was accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no column 'gx' in the header (t,rate)"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace calstand::solver

#include "store/import_export.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "store/capture_writer.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"
#include "temp_dir.hpp"
#include "text_files.hpp"

namespace calstand::store {
namespace {

using testing::TempDir;

const char* kMeta = R"({"format": "calstand-import/1",
 "site": {"latitude_deg": 30.53, "height_m": 20.0, "gravity_mps2": 9.7936},
 "table": {"outer_axis": [0,1,0], "inner_axis": [0,0,1]},
 "mount_rpy_deg": [0,0,0],
 "temperature_ref_c": 25.0,
 "sample_rate_hz": 50,
 "units": {"gyro": "deg/s", "accel": "m/s^2", "angle": "deg",
           "rate": "deg/s", "temperature": "degC", "time": "s"}}
)";

const char* kHeader =
    "t,step,outer_deg,inner_deg,outer_rate_dps,inner_rate_dps,temp_c,gx,gy,gz,ax,ay,az";

using test::read;
using test::write;

// Three steps with values 5, 2 (a rate step) and 9, numbers with awkward digits; step 5 rows
// come back after step 2 (steps need not be contiguous).
std::string good_csv() {
  std::string csv = std::string(kHeader) + "\n";
  int line = 0;
  auto row = [&](int step, double outer_rate) {
    const double t = 0.02 * line + 1.0 / 3.0;
    csv += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{}\n", t, step, outer_rate * t - 179.99,
                       90.0, outer_rate, 0, 25.0 + 1e-3 * line, 0.1 * line + 1e-17, -1.0 / 7.0,
                       4.2e-5, 1e-3, -9.7936 + 1e-6 * line, 1.0 / 3.0);
    ++line;
  };
  for (int i = 0; i < 40; ++i) row(5, 0.0);
  for (int i = 0; i < 30; ++i) row(2, 10.0);
  for (int i = 0; i < 20; ++i) row(9, 0.0);
  for (int i = 0; i < 10; ++i) row(5, 0.0);
  return csv;
}

struct ImportDir {
  TempDir dir;
  ImportDir(const std::string& meta = kMeta, const std::string& csv = good_csv()) {
    write(dir.path() / "meta.json", meta);
    write(dir.path() / "samples.csv", csv);
  }
};

int runs_in(Database& db) { return db.sql().execAndGet("SELECT COUNT(*) FROM runs").getInt(); }

// The InputError text of importing (meta, csv), checking that nothing was written.
std::string import_error(const std::string& meta, const std::string& csv) {
  ImportDir d(meta, csv);
  Database db(":memory:");
  try {
    import_run(db, d.dir.path());
  } catch (const core::InputError& e) {
    EXPECT_EQ(runs_in(db), 0);
    EXPECT_EQ(db.sql().execAndGet("SELECT COUNT(*) FROM sample_chunks").getInt(), 0);
    return e.what();
  }
  ADD_FAILURE() << "import succeeded";
  return "";
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

// The CSV with line `n` (1-based, header = 1) replaced.
std::string with_line(int n, const std::string& text) {
  std::stringstream in(good_csv());
  std::string out;
  std::string line;
  for (int i = 1; std::getline(in, line); ++i) out += (i == n ? text : line) + "\n";
  return out;
}

TEST(Import, CreatesOneCompletedStepPerStepValue) {
  ImportDir d;
  TempDir out;
  Database db(out.file("import.db"));
  const ImportResult r = import_run(db, d.dir.path());
  EXPECT_EQ(r.steps, 3u);
  EXPECT_EQ(r.samples, 100u);
  RunStore runs(db);
  const RunRecord run = runs.load_run(r.run);
  EXPECT_EQ(run.summary.status, "imported");
  EXPECT_EQ(run.summary.steps_done, 3u);
  EXPECT_EQ(run.station_snapshot["site"]["gravity_mps2"], 9.7936);
  ASSERT_EQ(run.steps.size(), 3u);
  EXPECT_EQ(run.steps[0].commanded["import_step"], 5);
  EXPECT_EQ(run.steps[0].commanded["mode"], "position");
  EXPECT_NEAR(run.steps[0].commanded["outer_deg"].get<double>(), -179.99, 1e-9);
  EXPECT_EQ(run.steps[1].commanded["import_step"], 2);
  EXPECT_EQ(run.steps[1].commanded["mode"], "rate");
  EXPECT_EQ(run.steps[1].commanded["outer_rate_dps"], 10.0);
  EXPECT_EQ(read_samples(db, r.run, 0, kImportDevice).size(), 50u);
  EXPECT_EQ(read_samples(db, r.run, 2, kImportDevice).size(), 20u);
  EXPECT_EQ(read_step_means(db, r.run).size(), 3u);
  EXPECT_EQ(db.sql().execAndGet("PRAGMA integrity_check").getString(), "ok");
}

TEST(Import, ExactEncodingKeepsEveryDigit) {
  ImportDir d;
  Database db(":memory:");
  const auto r = import_run(db, d.dir.path());
  const auto s = read_samples(db, r.run, 1, kImportDevice);
  ASSERT_EQ(s.size(), 30u);
  EXPECT_EQ(s[0].gyro_dps.y(), -1.0 / 7.0);
  EXPECT_EQ(s[0].accel_mps2.z(), 1.0 / 3.0);
  EXPECT_EQ(s[0].receive_time_s, 0.02 * 40 + 1.0 / 3.0);
}

TEST(ImportMetaErrors, UnitOtherThanTheFixedOneNamesTheField) {
  const auto e =
      import_error(replace(kMeta, R"("gyro": "deg/s")", R"("gyro": "rad/s")"), good_csv());
  EXPECT_CONTAINS(e, "meta.json");
  EXPECT_CONTAINS(e, "units.gyro");
}

TEST(ImportMetaErrors, WrongFormat) {
  EXPECT_CONTAINS(
      import_error(replace(kMeta, "calstand-import/1", "calstand-import/3"), good_csv()), "format");
}

TEST(Import, AVersionOneFolderIsAValidVersionTwoFolder) {
  // error-model.md: "A /1 folder stays valid" under /2.
  ImportDir one;
  ImportDir two(replace(kMeta, "calstand-import/1", "calstand-import/2"));
  Database db(":memory:");
  const auto r1 = import_run(db, one.dir.path());
  const auto r2 = import_run(db, two.dir.path());
  EXPECT_EQ(r2.steps, r1.steps);
  RunStore runs(db);
  const RunRecord a = runs.load_run(r1.run);
  const RunRecord b = runs.load_run(r2.run);
  EXPECT_EQ(b.summary.procedure_name, "calstand-import/2");
  for (std::size_t i = 0; i < a.steps.size(); ++i) {
    EXPECT_EQ(b.steps[i].commanded, a.steps[i].commanded);
    EXPECT_EQ(b.steps[i].label, a.steps[i].label);
    const auto sa = read_samples(db, r1.run, i, kImportDevice);
    const auto sb = read_samples(db, r2.run, i, kImportDevice);
    ASSERT_EQ(sa.size(), sb.size());
    for (std::size_t k = 0; k < sa.size(); ++k) {
      EXPECT_EQ(sa[k].gyro_dps, sb[k].gyro_dps);
      EXPECT_EQ(sa[k].temperature_c, sb[k].temperature_c);
    }
  }
}

TEST(ImportMetaErrors, MissingRequiredField) {
  EXPECT_CONTAINS(import_error(replace(kMeta, R"("sample_rate_hz": 50,)", ""), good_csv()),
                  "sample_rate_hz");
}

TEST(ImportMetaErrors, UnknownField) {
  EXPECT_CONTAINS(
      import_error(replace(kMeta, R"("sample_rate_hz")", R"("sample_rate": 1, "sample_rate_hz")"),
                   good_csv()),
      "sample_rate");
}

TEST(ImportMetaErrors, NonUnitAxis) {
  EXPECT_CONTAINS(import_error(replace(kMeta, "[0,1,0]", "[0,2,0]"), good_csv()),
                  "table.outer_axis: must be a unit vector");
}

TEST(ImportMetaErrors, JsonSyntaxNamesLine) {
  EXPECT_CONTAINS(
      import_error(replace(kMeta, R"("height_m": 20.0,)", R"("height_m": 20.0,,)"), good_csv()),
      "meta.json:2:");
}

TEST(ImportCsvErrors, HeaderMustBeExact) {
  EXPECT_CONTAINS(import_error(kMeta, with_line(1, replace(kHeader, "temp_c", "temperature"))),
                  "samples.csv:1: the header must be exactly");
}

TEST(ImportCsvErrors, WrongColumnCountNamesLine) {
  EXPECT_CONTAINS(import_error(kMeta, with_line(4, "1,2,3,4,5,6,7,8,9,10,11,12")),
                  "samples.csv:4: expected 13 columns, got 12");
  EXPECT_CONTAINS(import_error(kMeta, with_line(5, "1,2,3,4,5,6,7,8,9,10,11,12,13,14")),
                  "samples.csv:5: expected 13 columns, got 14");
}

TEST(ImportCsvErrors, NonFiniteNumbersNameLineAndColumn) {
  EXPECT_CONTAINS(import_error(kMeta, with_line(3, "1,5,0,0,0,0,25,nan,0,0,0,0,9.8")),
                  "samples.csv:3: column gx: 'nan' is not a finite number");
  EXPECT_CONTAINS(import_error(kMeta, with_line(3, "1,5,0,0,0,0,25,0,0,0,0,-inf,9.8")),
                  "samples.csv:3: column ay: '-inf' is not a finite number");
  EXPECT_CONTAINS(import_error(kMeta, with_line(3, "1,5,0,0,0,0,1e999,0,0,0,0,0,9.8")),
                  "samples.csv:3: column temp_c: '1e999' is not a number");
}

TEST(ImportCsvErrors, NotANumber) {
  EXPECT_CONTAINS(import_error(kMeta, with_line(7, "1,5,0,0,0,0,25,0,0,0,0,abc,9.8")),
                  "samples.csv:7: column ay: 'abc' is not a number");
  EXPECT_CONTAINS(import_error(kMeta, with_line(7, "1,5,0,,0,0,25,0,0,0,0,0,9.8")),
                  "samples.csv:7: column inner_deg: '' is not a number");
}

TEST(ImportCsvErrors, NonIntegerStep) {
  EXPECT_CONTAINS(import_error(kMeta, with_line(2, "1,1.5,0,0,0,0,25,0,0,0,0,0,9.8")),
                  "samples.csv:2: column step: '1.5' is not an integer");
}

TEST(ImportCsvErrors, NoSamplesAndBlankLines) {
  EXPECT_CONTAINS(import_error(kMeta, std::string(kHeader) + "\n"), "no samples");
  EXPECT_CONTAINS(import_error(kMeta, with_line(10, "")), "samples.csv:10: empty line");
}

TEST(ImportCsvErrors, MissingFile) {
  ImportDir d;
  std::filesystem::remove(d.dir.path() / "samples.csv");
  Database db(":memory:");
  try {
    import_run(db, d.dir.path());
    FAIL();
  } catch (const core::InputError& e) {
    EXPECT_CONTAINS(e.what(), "samples.csv: cannot open the file");
  }
  EXPECT_EQ(runs_in(db), 0);
}

TEST(ImportExport, ExportOfAnImportIsBitExactOnReimport) {
  ImportDir d;
  TempDir out;
  Database db(out.file("rt.db"));
  const auto first = import_run(db, d.dir.path());
  export_run(db, first.run, out.path() / "a");
  const auto second = import_run(db, out.path() / "a");
  export_run(db, second.run, out.path() / "b");
  const std::string a = read(out.path() / "a" / "samples.csv");
  EXPECT_EQ(a, read(out.path() / "b" / "samples.csv"));
  EXPECT_EQ(read(out.path() / "a" / "meta.json"), read(out.path() / "b" / "meta.json"));
  EXPECT_EQ(second.samples, first.samples);
  EXPECT_EQ(second.steps, first.steps);

  // Every number of the original survives: compare field by field as doubles, rows grouped
  // by step in order of first appearance.
  auto rows = [](const std::string& csv) {
    std::map<long, std::vector<std::vector<double>>> by_step;
    std::vector<long> order;
    std::stringstream in(csv);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      std::vector<double> v;
      std::stringstream fields(line);
      std::string f;
      while (std::getline(fields, f, ',')) v.push_back(std::stod(f));
      const long step = std::lround(v[1]);
      if (!by_step.count(step)) order.push_back(step);
      by_step[step].push_back(v);
    }
    std::vector<std::vector<double>> flat;
    for (long s : order) flat.insert(flat.end(), by_step[s].begin(), by_step[s].end());
    return flat;
  };
  EXPECT_EQ(rows(a), rows(good_csv()));
}

TEST(Export, RecordedRunUsesStationSnapshotAndTelemetry) {
  TempDir out;
  Database db(out.file("rec.db"));
  RunStore runs(db);
  NewRun nr;
  nr.procedure_name = "two-position";
  nr.station_snapshot = nlohmann::json::parse(R"({"site": {"latitude_deg": 30.5, "height_m": 25},
      "table": {"outer_axis": [0,1,0], "inner_axis": [0,0,1]},
      "imus": [{"name": "imu0", "mount_rpy_deg": [0, 0, 90]}]})");
  const auto run = runs.create_run(nr);
  const auto step = runs.add_steps(run, {{"capture", "c", {{"outer_deg", 0}}, "steps[0]"}})[0];
  core::TableState t0;
  t0.time_s = 0.0;
  t0.outer.angle_deg = 170.0;
  core::TableState t1 = t0;
  t1.time_s = 1.0;
  t1.outer.angle_deg = -170.0;  // crossed the wrap: 20 deg forward
  runs.add_table_telemetry(run, std::vector<core::TableState>{t0, t1});
  runs.mark_step_running(run, 0, 1, {0.0, "t"});
  {
    CaptureWriter w(db.path());
    const auto s = w.open_stream(run, step, 1, "imu0");
    for (int i = 0; i <= 100; ++i) {
      core::ImuSample x;
      x.receive_time_s = 0.01 * i;
      x.sequence = static_cast<std::uint32_t>(i);
      ASSERT_TRUE(w.push(s, x));
    }
    w.commit_step(step, 1);
  }
  runs.mark_step_completed(run, 0, 1, {1.0, "t"});
  export_run(db, run, out.path() / "x");
  const auto meta = nlohmann::json::parse(read(out.path() / "x" / "meta.json"));
  EXPECT_EQ(meta["format"], "calstand-import/1");
  EXPECT_EQ(meta["mount_rpy_deg"], nlohmann::json::parse("[0, 0, 90]"));
  EXPECT_EQ(meta["sample_rate_hz"], 100.0);
  // The middle sample (t = 0.5 s) sits at the wrap, not at 0 deg.
  std::stringstream csv(read(out.path() / "x" / "samples.csv"));
  std::string line;
  for (int i = 0; i <= 51; ++i) std::getline(csv, line);
  EXPECT_EQ(line.substr(0, line.find(',', line.find(',', line.find(',') + 1) + 1)), "0.5,0,-180");
  // A recorded run's export is a valid import.
  Database other(":memory:");
  EXPECT_EQ(import_run(other, out.path() / "x").samples, 101u);
}

TEST(Export, UnknownRunOrDeviceIsAnInputError) {
  ImportDir d;
  TempDir out;
  Database db(":memory:");
  const auto r = import_run(db, d.dir.path());
  EXPECT_THROW(export_run(db, r.run + 1, out.path()), core::InputError);
  EXPECT_THROW(export_run(db, r.run, out.path(), {"imu7"}), core::InputError);
}

}  // namespace
}  // namespace calstand::store

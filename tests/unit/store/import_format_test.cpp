// calstand-import/2: every unit, with and without step, table columns and temperature,
// labelled sections, any column order, the export of such a run, and every bad input naming
// its file, line and field with nothing written.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "store/import_export.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"
#include "store/step_data.hpp"
#include "temp_dir.hpp"
#include "text_files.hpp"

namespace calstand::store {
namespace {

using nlohmann::json;
using testing::TempDir;

constexpr double kG0 = 9.80665;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;

// A hand-held session: no table, gravity given, physical units.
json base_meta() {
  return json::parse(R"({"format": "calstand-import/2",
    "site": {"latitude_deg": 45.41, "height_m": 12.0, "gravity_mps2": 9.81744},
    "sample_rate_hz": 100,
    "units": {"gyro": "deg/s", "accel": "m/s^2", "time": "s"}})");
}

json table_meta() {
  json m = base_meta();
  m["table"] = {{"outer_axis", {0, 1, 0}}, {"inner_axis", {0, 0, 1}}};
  m["units"]["angle"] = "deg";
  m["units"]["rate"] = "deg/s";
  return m;
}

// The physical truth of sample i: gyro [deg/s], accel [m/s^2], temperature [degC].
double gyro_truth(int i, int axis) { return 0.01 * i - 0.3 * axis + 1.0 / 7.0; }
double accel_truth(int i, int axis) { return axis == 2 ? 9.81 - 1e-4 * i : 0.02 * axis - 1e-5 * i; }

struct Column {
  std::string name;
  std::function<std::string(int)> value;  // of row i
};

// A samples.csv of `rows` rows with `columns` in that order.
std::string csv_of(const std::vector<Column>& columns, int rows) {
  std::string out;
  for (std::size_t c = 0; c < columns.size(); ++c) out += (c ? "," : "") + columns[c].name;
  out += "\n";
  for (int i = 0; i < rows; ++i) {
    for (std::size_t c = 0; c < columns.size(); ++c) out += (c ? "," : "") + columns[c].value(i);
    out += "\n";
  }
  return out;
}

std::string num(double v) { return fmt::format("{:.17g}", v); }

// The required columns, gyro in `gyro_unit` and accel in `accel_unit` (counts: offset 32768,
// 83.78 counts per deg/s, 410 counts per m/s^2 on x, other scales on y and z).
std::vector<Column> sensor_columns(const std::string& gyro_unit = "deg/s",
                                   const std::string& accel_unit = "m/s^2") {
  std::vector<Column> c;
  c.push_back({"t", [](int i) { return num(0.01 * i); }});
  const char* g_names[] = {"gx", "gy", "gz"};
  const char* a_names[] = {"ax", "ay", "az"};
  for (int axis = 0; axis < 3; ++axis) {
    c.push_back({g_names[axis], [=](int i) {
                   const double v = gyro_truth(i, axis);
                   if (gyro_unit == "rad/s") return num(v / kDegPerRad);
                   if (gyro_unit == "counts") return num(32768.0 + v * (83.78 + axis));
                   return num(v);
                 }});
  }
  for (int axis = 0; axis < 3; ++axis) {
    c.push_back({a_names[axis], [=](int i) {
                   const double v = accel_truth(i, axis);
                   if (accel_unit == "g") return num(v / kG0);
                   if (accel_unit == "counts") return num(32768.0 + v * (410.0 + axis));
                   return num(v);
                 }});
  }
  return c;
}

json nominal() {
  return json::parse(R"({"gyro": {"offset_counts": [32768, 32768, 32768],
                                  "counts_per_dps": [83.78, 84.78, 85.78]},
                         "accel": {"offset_counts": [32768, 32768, 32768],
                                   "counts_per_mps2": [410, 411, 412]}})");
}

using test::read;
using test::write;

struct Folder {
  TempDir dir;
  Folder(const json& meta, const std::string& csv) {
    write(dir.path() / "meta.json", meta.dump(2));
    write(dir.path() / "samples.csv", csv);
  }
};

int count(Database& db, const char* table) {
  return db.sql().execAndGet(std::string("SELECT COUNT(*) FROM ") + table).getInt();
}

// The error text of importing (meta, csv); checks that nothing was written.
std::string import_error_text(const json& meta, const std::string& csv) {
  Folder f(meta, csv);
  Database db(":memory:");
  try {
    import_run(db, f.dir.path());
  } catch (const core::InputError& e) {
    EXPECT_EQ(count(db, "runs"), 0);
    EXPECT_EQ(count(db, "steps"), 0);
    EXPECT_EQ(count(db, "sample_chunks"), 0);
    EXPECT_EQ(count(db, "table_telemetry"), 0);
    std::string what = e.what();
    // Name the files by their names only.
    for (const char* name : {"meta.json", "samples.csv"}) {
      const std::string full = (f.dir.path() / name).string();
      for (auto at = what.find(full); at != std::string::npos; at = what.find(full)) {
        what.replace(at, full.size(), name);
      }
    }
    return what;
  }
  ADD_FAILURE() << "import succeeded";
  return "";
}

std::vector<Column> with(std::vector<Column> c, const std::vector<Column>& more) {
  c.insert(c.end(), more.begin(), more.end());
  return c;
}

Column step_column(int rows_per_step) {
  return {"step", [=](int i) { return std::to_string(10 + i / rows_per_step); }};
}
Column temp_column() {
  return {"temp_c", [](int i) { return num(20.0 + 0.001 * i); }};
}
std::vector<Column> table_columns() {
  return {{"outer_deg", [](int) { return num(90.0); }},
          {"inner_deg", [](int) { return num(-45.0); }},
          {"outer_rate_dps", [](int) { return num(0.0); }},
          {"inner_rate_dps", [](int) { return num(0.0); }}};
}

// ---- units ----

struct UnitCase {
  const char* gyro;
  const char* accel;
};

/// The case by its units in ctest's test names (not the struct's bytes).
void PrintTo(const UnitCase& u, std::ostream* os) { *os << u.gyro << " and " << u.accel; }

class Import2Units : public ::testing::TestWithParam<UnitCase> {};

TEST_P(Import2Units, SamplesAreStoredInDegPerSecondAndMetresPerSecondSquared) {
  const UnitCase u = GetParam();
  json meta = base_meta();
  meta["units"]["gyro"] = u.gyro;
  meta["units"]["accel"] = u.accel;
  const json n = nominal();
  if (std::string(u.gyro) == "counts") meta["nominal"]["gyro"] = n["gyro"];
  if (std::string(u.accel) == "counts") meta["nominal"]["accel"] = n["accel"];
  Folder f(meta, csv_of(sensor_columns(u.gyro, u.accel), 50));
  Database db(":memory:");
  const ImportResult r = import_run(db, f.dir.path());
  EXPECT_EQ(r.samples, 50u);
  const auto s = read_samples(db, r.run, 0, kImportDevice);
  ASSERT_EQ(s.size(), 50u);
  for (int i = 0; i < 50; ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_NEAR(s[i].gyro_dps[axis], gyro_truth(i, axis), 1e-12) << u.gyro << " " << i;
      EXPECT_NEAR(s[i].accel_mps2[axis], accel_truth(i, axis), 1e-12) << u.accel << " " << i;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(EveryUnit, Import2Units,
                         ::testing::Values(UnitCase{"deg/s", "m/s^2"}, UnitCase{"rad/s", "g"},
                                           UnitCase{"counts", "counts"},
                                           UnitCase{"deg/s", "counts"}, UnitCase{"counts", "m/s^2"},
                                           UnitCase{"rad/s", "m/s^2"}, UnitCase{"deg/s", "g"}));

// ---- steps, table, temperature, sections ----

TEST(Import2, WithoutStepOneRecordingStepOfUnknownOrientation) {
  Folder f(base_meta(), csv_of(sensor_columns(), 30));
  Database db(":memory:");
  const ImportResult r = import_run(db, f.dir.path());
  EXPECT_EQ(r.steps, 1u);
  RunStore runs(db);
  const RunRecord run = runs.load_run(r.run);
  EXPECT_EQ(run.summary.procedure_name, "calstand-import/2");
  ASSERT_EQ(run.steps.size(), 1u);
  EXPECT_EQ(run.steps[0].label, "recording");
  EXPECT_EQ(run.steps[0].commanded,
            json::parse(R"({"mode": "recording", "orientation": "unknown"})"));
  EXPECT_FALSE(orientation_known(run.steps[0]));
  EXPECT_FALSE(orientation_known(db, r.run));
  // No table rows; the table state reads NaN, not zeros; no temperature column: NaN.
  EXPECT_EQ(count(db, "table_telemetry"), 0);
  const auto data = read_step_data(db, r.run, kImportDevice);
  ASSERT_EQ(data.size(), 1u);
  ASSERT_EQ(data[0].table.size(), 30u);
  EXPECT_TRUE(std::isnan(data[0].table[7].outer_deg));
  EXPECT_TRUE(std::isnan(data[0].table[7].inner_rate_dps));
  EXPECT_TRUE(std::isnan(data[0].samples[7].temperature_c));
  const auto means = read_step_means(db, r.run);
  ASSERT_EQ(means.size(), 1u);
  EXPECT_TRUE(std::isnan(means[0].temperature_c));
  EXPECT_NEAR(means[0].gyro_dps[0], gyro_truth(0, 0) + 0.01 * 14.5, 1e-12);
}

TEST(Import2, WithStepAndNoTableOneStepPerValue) {
  Folder f(base_meta(), csv_of(with(sensor_columns(), {step_column(10), temp_column()}), 30));
  json meta = base_meta();
  meta["units"]["temperature"] = "degC";
  write(f.dir.path() / "meta.json", meta.dump());
  Database db(":memory:");
  const ImportResult r = import_run(db, f.dir.path());
  EXPECT_EQ(r.steps, 3u);
  const RunRecord run = RunStore(db).load_run(r.run);
  ASSERT_EQ(run.steps.size(), 3u);
  EXPECT_EQ(run.steps[1].label, "step 11");
  EXPECT_EQ(run.steps[1].commanded,
            json::parse(R"({"import_step": 11, "mode": "recording", "orientation": "unknown"})"));
  const auto s = read_samples(db, r.run, 2, kImportDevice);
  ASSERT_EQ(s.size(), 10u);
  EXPECT_DOUBLE_EQ(s[0].temperature_c, 20.02);
  EXPECT_FALSE(orientation_known(db, r.run));
}

TEST(Import2, WithTableColumnsAsVersionOne) {
  Folder f(table_meta(),
           csv_of(with(sensor_columns(), with({step_column(15)}, table_columns())), 30));
  Database db(":memory:");
  const ImportResult r = import_run(db, f.dir.path());
  const RunRecord run = RunStore(db).load_run(r.run);
  ASSERT_EQ(run.steps.size(), 2u);
  EXPECT_EQ(run.steps[0].label, "step 10");
  EXPECT_EQ(run.steps[0].commanded["mode"], "position");
  EXPECT_NEAR(run.steps[0].commanded["outer_deg"].get<double>(), 90.0, 1e-9);
  EXPECT_FALSE(run.steps[0].commanded.contains("orientation"));
  EXPECT_TRUE(orientation_known(db, r.run));
  EXPECT_EQ(count(db, "table_telemetry"), 30);
  const auto data = read_step_data(db, r.run, kImportDevice);
  EXPECT_EQ(data[1].table[3].inner_deg, -45.0);
}

TEST(Import2, WithTableColumnsButNoStepOneRecordingWithItsTableState) {
  Folder f(table_meta(), csv_of(with(sensor_columns(), table_columns()), 20));
  Database db(":memory:");
  const ImportResult r = import_run(db, f.dir.path());
  const RunRecord run = RunStore(db).load_run(r.run);
  ASSERT_EQ(run.steps.size(), 1u);
  EXPECT_EQ(run.steps[0].label, "recording");
  EXPECT_EQ(run.steps[0].commanded, json::parse(R"({"mode": "recording"})"));
  EXPECT_TRUE(orientation_known(db, r.run));
  EXPECT_EQ(count(db, "table_telemetry"), 20);
}

TEST(Import2, AnyColumnOrderGivesTheSameRun) {
  std::vector<Column> columns = with(sensor_columns(), {step_column(5)});
  Folder a(base_meta(), csv_of(columns, 20));
  std::reverse(columns.begin(), columns.end());
  std::rotate(columns.begin(), columns.begin() + 3, columns.end());
  Folder b(base_meta(), csv_of(columns, 20));
  Database db(":memory:");
  const auto ra = import_run(db, a.dir.path());
  const auto rb = import_run(db, b.dir.path());
  for (std::size_t step = 0; step < 4; ++step) {
    const auto sa = read_samples(db, ra.run, step, kImportDevice);
    const auto sb = read_samples(db, rb.run, step, kImportDevice);
    ASSERT_EQ(sa.size(), 5u);
    ASSERT_EQ(sb.size(), 5u);
    for (std::size_t i = 0; i < 5; ++i) {
      EXPECT_EQ(sa[i].receive_time_s, sb[i].receive_time_s);
      EXPECT_EQ(sa[i].gyro_dps, sb[i].gyro_dps);
      EXPECT_EQ(sa[i].accel_mps2, sb[i].accel_mps2);
    }
  }
}

json ferraris_meta() {
  json m = base_meta();
  m["sections"] = json::parse(R"({
    "10": {"label": "x_p", "kind": "static", "up": "+x"},
    "11": {"label": "x_rot", "kind": "turn", "axis": "-x", "angle_deg": 360}})");
  return m;
}

TEST(Import2, SectionsLabelTheirSteps) {
  Folder f(ferraris_meta(), csv_of(with(sensor_columns(), {step_column(10)}), 30));
  Database db(":memory:");
  const ImportResult r = import_run(db, f.dir.path());
  const RunRecord run = RunStore(db).load_run(r.run);
  ASSERT_EQ(run.steps.size(), 3u);
  EXPECT_EQ(run.steps[0].label, "x_p");
  EXPECT_EQ(run.steps[0].commanded, json::parse(R"({"import_step": 10, "mode": "static",
      "orientation": "unknown", "section": {"label": "x_p", "kind": "static", "up": "+x"}})"));
  EXPECT_EQ(run.steps[1].label, "x_rot");
  EXPECT_EQ(run.steps[1].commanded["mode"], "turn");
  EXPECT_EQ(run.steps[1].commanded["section"],
            json::parse(R"({"label": "x_rot", "kind": "turn", "axis": "-x", "angle_deg": 360})"));
  EXPECT_EQ(run.steps[2].label, "step 12");  // no section: unlabelled
  EXPECT_EQ(run.steps[2].commanded["mode"], "recording");
}

TEST(Import2, ExportIsAVersionTwoFolderThatReimportsBitExactly) {
  json meta = ferraris_meta();
  meta["units"]["gyro"] = "counts";
  meta["nominal"]["gyro"] = nominal()["gyro"];
  meta["units"]["temperature"] = "degC";
  Folder f(meta, csv_of(with(sensor_columns("counts"), {temp_column(), step_column(10)}), 30));
  TempDir out;
  Database db(out.file("x.db"));
  const auto first = import_run(db, f.dir.path());
  export_run(db, first.run, out.path() / "a");
  const json exported = json::parse(read(out.path() / "a" / "meta.json"));
  EXPECT_EQ(exported["format"], "calstand-import/2");
  EXPECT_EQ(exported["units"]["gyro"], "deg/s");  // converted on import
  EXPECT_FALSE(exported.contains("nominal"));
  EXPECT_FALSE(exported.contains("table"));
  EXPECT_EQ(exported["sections"], meta["sections"]);
  const std::string a = read(out.path() / "a" / "samples.csv");
  EXPECT_EQ(a.substr(0, a.find('\n')), "t,step,temp_c,gx,gy,gz,ax,ay,az");
  const auto second = import_run(db, out.path() / "a");
  export_run(db, second.run, out.path() / "b");
  EXPECT_EQ(read(out.path() / "b" / "samples.csv"), a);
  EXPECT_EQ(read(out.path() / "b" / "meta.json"), read(out.path() / "a" / "meta.json"));
  const auto s1 = read_samples(db, first.run, 1, kImportDevice);
  const auto s2 = read_samples(db, second.run, 1, kImportDevice);
  ASSERT_EQ(s1.size(), s2.size());
  for (std::size_t i = 0; i < s1.size(); ++i) EXPECT_EQ(s1[i].gyro_dps, s2[i].gyro_dps);
  EXPECT_EQ(RunStore(db).load_run(second.run).steps[0].label, "x_p");

  // Without step the export has no step column, and the reimport is again one recording.
  Folder g(base_meta(), csv_of(sensor_columns(), 10));
  const auto plain = import_run(db, g.dir.path());
  export_run(db, plain.run, out.path() / "c");
  const std::string c = read(out.path() / "c" / "samples.csv");
  EXPECT_EQ(c.substr(0, c.find('\n')), "t,gx,gy,gz,ax,ay,az");
  const auto again = import_run(db, out.path() / "c");
  EXPECT_EQ(RunStore(db).load_run(again.run).steps[0].label, "recording");
}

// ---- errors: file, line and field named, nothing written ----

std::string sensor_csv() { return csv_of(sensor_columns(), 20); }

TEST(Import2MetaErrors, CountsNeedTheirNominalAndOnlyCounts) {
  json m = base_meta();
  m["units"]["gyro"] = "counts";
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()),
                  "meta.json: nominal.gyro: required when units.gyro");
  m = base_meta();
  m["units"]["accel"] = "counts";
  m["nominal"]["gyro"] = nominal()["gyro"];
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()),
                  "meta.json: nominal.gyro: only for units.gyro 'counts', but units.gyro is "
                  "'deg/s'");
  m = base_meta();
  m["units"]["accel"] = "counts";
  m["nominal"]["accel"] = {{"offset_counts", {0, 0, 0}}};
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()), "nominal.accel");
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()), "counts_per_mps2");
  m["nominal"]["accel"]["counts_per_mps2"] = {410, 0, 410};
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()),
                  "meta.json: nominal.accel.counts_per_mps2[1]");
}

TEST(Import2MetaErrors, UnitsNameTheField) {
  json m = base_meta();
  m["units"]["gyro"] = "deg/h";
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()), "meta.json: units.gyro");
  m = base_meta();
  m["units"]["accel"] = "mg";
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()), "meta.json: units.accel");
  m = base_meta();
  m["units"].erase("time");
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()), "time");
  m = base_meta();
  m["units"]["angle"] = "deg";
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()), "meta.json: units.angle: only with table");
  m = table_meta();
  m["units"].erase("rate");
  EXPECT_CONTAINS(import_error_text(m, csv_of(with(sensor_columns(), table_columns()), 5)),
                  "meta.json: units.rate: required with table");
}

TEST(Import2MetaErrors, GravityRequiredWithoutTable) {
  json m = base_meta();
  m["site"].erase("gravity_mps2");
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()),
                  "meta.json: site.gravity_mps2: required without table");
}

TEST(Import2MetaErrors, UnknownFieldsAreErrors) {
  json m = base_meta();
  m["colour"] = "red";
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()), "unknown property \"colour\"");
  m = base_meta();
  m["units"]["magnetometer"] = "uT";
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()), "magnetometer");
  m = base_meta();
  m["mount_rpy_deg"] = {0, 0, 0};
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()), "meta.json: mount_rpy_deg: only with table");
}

TEST(Import2MetaErrors, SectionsAreChecked) {
  const std::string csv = csv_of(with(sensor_columns(), {step_column(10)}), 30);
  json m = ferraris_meta();
  m["sections"]["10"]["colour"] = "red";
  EXPECT_CONTAINS(import_error_text(m, csv), "sections[\"10\"]");
  EXPECT_CONTAINS(import_error_text(m, csv), "colour");
  m = ferraris_meta();
  m["sections"]["10"].erase("up");
  EXPECT_CONTAINS(import_error_text(m, csv), "up");
  m = ferraris_meta();
  m["sections"]["10"]["up"] = "x";
  EXPECT_CONTAINS(import_error_text(m, csv), "up");
  m = ferraris_meta();
  m["sections"]["11"]["up"] = "+z";  // a turn has no up
  EXPECT_CONTAINS(import_error_text(m, csv), "up");
  m = ferraris_meta();
  m["sections"]["11"]["label"] = "x_p";
  EXPECT_CONTAINS(import_error_text(m, csv),
                  "meta.json: sections[\"11\"].label: 'x_p' is also the label of section 10");
  m = ferraris_meta();
  m["sections"]["99"] = {{"label", "z_m"}, {"kind", "static"}, {"up", "-z"}};
  EXPECT_CONTAINS(
      import_error_text(m, csv),
      "meta.json: sections[\"99\"]: no sample of samples.csv has step 99 (label 'z_m')");
  m = ferraris_meta();
  m["sections"]["ten"] = {{"label", "z_m"}, {"kind", "static"}, {"up", "-z"}};
  EXPECT_CONTAINS(import_error_text(m, csv), "ten");
  EXPECT_CONTAINS(import_error_text(ferraris_meta(), sensor_csv()),
                  "meta.json: sections: need the step column in samples.csv");
  m = ferraris_meta();
  m["table"] = table_meta()["table"];
  m["units"] = table_meta()["units"];
  EXPECT_CONTAINS(
      import_error_text(
          m, csv_of(with(sensor_columns(), with({step_column(10)}, table_columns())), 30)),
      "meta.json: sections: only without table");
}

TEST(Import2CsvErrors, TableAndItsColumnsComeTogether) {
  EXPECT_CONTAINS(import_error_text(table_meta(), sensor_csv()),
                  "samples.csv:1: no table columns (outer_deg, inner_deg, outer_rate_dps, "
                  "inner_rate_dps), but meta.json has a table");
  EXPECT_CONTAINS(
      import_error_text(base_meta(), csv_of(with(sensor_columns(), table_columns()), 5)),
      "samples.csv:1: column outer_deg: the table columns need meta.json's table");
  std::vector<Column> three = table_columns();
  three.pop_back();
  EXPECT_CONTAINS(import_error_text(table_meta(), csv_of(with(sensor_columns(), three), 5)),
                  "samples.csv:1: column outer_deg: the four table columns come all or none; "
                  "missing inner_rate_dps");
}

TEST(Import2CsvErrors, TemperatureUnitAndColumnComeTogether) {
  json m = base_meta();
  m["units"]["temperature"] = "degC";
  EXPECT_CONTAINS(import_error_text(m, sensor_csv()),
                  "meta.json: units.temperature: given, but samples.csv has no temp_c column");
  EXPECT_CONTAINS(
      import_error_text(base_meta(), csv_of(with(sensor_columns(), {temp_column()}), 5)),
      "meta.json: units.temperature: required with the temp_c column of samples.csv");
}

TEST(Import2CsvErrors, HeaderNamesTheColumn) {
  EXPECT_CONTAINS(
      import_error_text(base_meta(),
                        csv_of(with(sensor_columns(), {{"mx", [](int) { return "1"; }}}), 5)),
      "samples.csv:1: column 'mx' is not a column of calstand-import/2");
  EXPECT_CONTAINS(
      import_error_text(base_meta(),
                        csv_of(with(sensor_columns(), {{"gx", [](int) { return "1"; }}}), 5)),
      "samples.csv:1: column 'gx' appears twice in the header");
  std::vector<Column> no_gz = sensor_columns();
  no_gz.erase(no_gz.begin() + 3);
  EXPECT_CONTAINS(import_error_text(base_meta(), csv_of(no_gz, 5)),
                  "samples.csv:1: column gz is missing");
}

TEST(Import2CsvErrors, RowsNameLineAndColumn) {
  std::vector<Column> c = sensor_columns("counts");
  c[2].value = [](int i) { return i == 3 ? std::string("x") : std::string("32768"); };
  json m = base_meta();
  m["units"]["gyro"] = "counts";
  m["nominal"]["gyro"] = nominal()["gyro"];
  EXPECT_CONTAINS(import_error_text(m, csv_of(c, 10)),
                  "samples.csv:5: column gy: 'x' is not a number");
  std::vector<Column> s = with(sensor_columns(), {step_column(2)});
  s.back().value = [](int i) { return i == 4 ? std::string("2.5") : std::string("1"); };
  EXPECT_CONTAINS(import_error_text(base_meta(), csv_of(s, 10)),
                  "samples.csv:6: column step: '2.5' is not an integer");
  std::string short_row = sensor_csv() + "1,2,3\n";
  EXPECT_CONTAINS(import_error_text(base_meta(), short_row),
                  "samples.csv:22: expected 7 columns, got 3");
  EXPECT_CONTAINS(import_error_text(base_meta(), "t,gx,gy,gz,ax,ay,az\n"), "no samples");
}

// ---- streaming: batches, steps that come back, refusals late in the file ----

// A table session whose step values come back later in the file (10, 11, 10, 12, 11), with an
// angle near +-180 deg (a circular mean) and a rate step: the rows of a value form one step, in
// file order, whatever the batch size.
std::vector<Column> interleaved_table_columns() {
  const auto step_of = [](int i) {
    static constexpr int kSteps[] = {10, 11, 10, 12, 11};
    return kSteps[i / 7];
  };
  return with(sensor_columns(),
              {{"step", [=](int i) { return std::to_string(step_of(i)); }},
               {"outer_deg",
                [=](int i) { return num(step_of(i) == 11 ? (i % 2 ? 179.99 : -179.98) : 30.0); }},
               {"inner_deg", [](int i) { return num(0.001 * i); }},
               {"outer_rate_dps", [=](int i) { return num(step_of(i) == 12 ? 10.0 + i : 0.0); }},
               {"inner_rate_dps", [](int) { return num(0.0); }}});
}

TEST(Import2Streaming, StepsThatComeBackJoinTheirStepWhateverTheBatch) {
  Folder f(table_meta(), csv_of(interleaved_table_columns(), 35));
  Database db(":memory:");
  std::vector<std::int64_t> runs;
  for (const std::size_t batch : {std::size_t{8192}, std::size_t{3}, std::size_t{1}}) {
    ImportRunOptions options;
    options.batch = batch;
    std::vector<double> fractions;
    options.progress = [&](double fraction, std::uint64_t) { fractions.push_back(fraction); };
    const ImportResult r = import_run(db, f.dir.path(), options);
    EXPECT_EQ(r.steps, 3u);
    EXPECT_EQ(r.samples, 35u);
    ASSERT_FALSE(fractions.empty());
    EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
    EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
    runs.push_back(r.run);
  }
  // Rows of step 10: 0-6 and 14-20; of 11: 7-13 and 28-34; of 12: 21-27.
  const std::vector<std::vector<int>> rows = {{0, 1, 2, 3, 4, 5, 6, 14, 15, 16, 17, 18, 19, 20},
                                              {7, 8, 9, 10, 11, 12, 13, 28, 29, 30, 31, 32, 33, 34},
                                              {21, 22, 23, 24, 25, 26, 27}};
  for (const std::int64_t run_id : runs) {
    const RunRecord run = RunStore(db).load_run(run_id);
    ASSERT_EQ(run.steps.size(), 3u);
    EXPECT_EQ(run.steps[0].label, "step 10");
    EXPECT_EQ(run.steps[1].label, "step 11");
    EXPECT_EQ(run.steps[2].label, "step 12");
    EXPECT_EQ(run.steps[0].commanded["mode"], "position");
    EXPECT_NEAR(run.steps[0].commanded["outer_deg"].get<double>(), 30.0, 1e-9);
    // The circular mean of 179.99 and -179.98 (7 and 7 of them) is 180.005, i.e. -179.995.
    EXPECT_NEAR(std::remainder(run.steps[1].commanded["outer_deg"].get<double>() + 179.995, 360.0),
                0.0, 1e-9);
    EXPECT_EQ(run.steps[2].commanded["mode"], "rate");
    EXPECT_NEAR(run.steps[2].commanded["outer_rate_dps"].get<double>(), 10.0 + 24.0, 1e-9);
    EXPECT_NEAR(run.steps[2].commanded["outer_start_deg"].get<double>(), 30.0, 1e-12);
    EXPECT_NEAR(run.steps[2].commanded["inner_start_deg"].get<double>(), 0.021, 1e-12);
    EXPECT_EQ(run.steps[0].origin.substr(run.steps[0].origin.size() - 13), "samples.csv:2");
    EXPECT_EQ(run.steps[2].origin.substr(run.steps[2].origin.size() - 14), "samples.csv:23");
    const auto data = read_step_data(db, run_id, kImportDevice);
    ASSERT_EQ(data.size(), 3u);
    for (std::size_t step = 0; step < 3; ++step) {
      const auto s = read_samples(db, run_id, step, kImportDevice);
      ASSERT_EQ(s.size(), rows[step].size());
      ASSERT_EQ(data[step].table.size(), rows[step].size());
      for (std::size_t k = 0; k < s.size(); ++k) {
        const int i = rows[step][k];
        EXPECT_EQ(s[k].receive_time_s, 0.01 * i);
        EXPECT_EQ(s[k].sequence, k);
        EXPECT_EQ(s[k].gyro_dps[1], gyro_truth(i, 1));
        EXPECT_EQ(s[k].accel_mps2[2], accel_truth(i, 2));
        EXPECT_EQ(data[step].table[k].inner_deg, 0.001 * i);
      }
      // The step's span covers its rows where they come back.
      EXPECT_DOUBLE_EQ(run.steps[step].started_clock_s.value(), 0.01 * rows[step].front());
      EXPECT_DOUBLE_EQ(run.steps[step].ended_clock_s.value(), 0.01 * rows[step].back());
    }
  }
  EXPECT_EQ(count(db, "table_telemetry"), 3 * 35);
}

TEST(Import2Streaming, ARefusalAtTheLastRowLeavesNothingAfterManyBatches) {
  // 20000 rows in batches of 1000: many chunks are written before the last row is read.
  std::vector<Column> c = with(sensor_columns(), table_columns());
  c[4].value = [](int i) { return i == 19999 ? std::string("nan") : num(accel_truth(i, 0)); };
  Folder f(table_meta(), csv_of(c, 20000));
  Database db(":memory:");
  ImportRunOptions options;
  options.batch = 1000;
  try {
    import_run(db, f.dir.path(), options);
    ADD_FAILURE() << "import succeeded";
  } catch (const core::InputError& e) {
    EXPECT_CONTAINS(std::string(e.what()), "samples.csv:20001: column ax");
  }
  for (const char* table : {"runs", "steps", "sample_chunks", "table_telemetry", "step_means"}) {
    EXPECT_EQ(count(db, table), 0) << table;
  }
  // A section whose step has no sample is found only at the end of the file: also nothing.
  json meta = ferraris_meta();
  meta["sections"]["99"] = {{"label", "z_p"}, {"kind", "static"}, {"up", "+z"}};
  Folder g(meta, csv_of(with(sensor_columns(), {step_column(1000)}), 5000));
  try {
    import_run(db, g.dir.path(), options);
    ADD_FAILURE() << "import succeeded";
  } catch (const core::InputError& e) {
    EXPECT_CONTAINS(std::string(e.what()), "no sample of");
  }
  for (const char* table : {"runs", "steps", "sample_chunks", "step_means"}) {
    EXPECT_EQ(count(db, table), 0) << table;
  }
}

}  // namespace
}  // namespace calstand::store

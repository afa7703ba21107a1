// Recordings written by independent writers (tests/support/write_recordings.py: MCAP from the
// specification, rosbag2's sqlite3 schema with a hand-written CDR encoder, Debian's
// python3-rosbag, a EuRoC folder) import to exactly the samples of the same recording's
// calstand-import/2 CSV; broken and ambiguous inputs are refused by name and position with
// nothing written.

#include "store/import_recording.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <random>

#include "core/error.hpp"
#include "store/import_export.hpp"
#include "store/recording_reader.hpp"
#include "store/sample_reader.hpp"
#include "temp_dir.hpp"
#include "text_files.hpp"

namespace calstand::store {
namespace {

using testing::TempDir;

constexpr int kSamples = 2000;

/// The recordings of write_recordings.py, written once for the suite.
class Recordings : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    const std::string cmd =
        fmt::format("/usr/bin/python3 {}/tests/support/write_recordings.py {} --samples {}",
                    CALSTAND_SOURCE_DIR, dir_->path().string(), kSamples);
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    Database db(":memory:");
    const ImportResult r = import_run(db, dir_->path() / "csv");
    reference_ = new std::vector<core::ImuSample>(read_samples(db, r.run, 0, kImportDevice));
  }
  static void TearDownTestSuite() {
    delete reference_;
    delete dir_;
  }

  static std::filesystem::path file(const std::string& name) { return dir_->path() / name; }

  static RecordingImportOptions site() {
    RecordingImportOptions o;
    o.latitude_deg = 45.0;
    o.height_m = 0.0;
    o.gravity_mps2 = 9.8062;
    return o;
  }

  // Imports `name` and expects the reference's samples bit for bit.
  static RecordingImportResult expect_same_as_csv(const std::string& name,
                                                  RecordingImportOptions o = site()) {
    Database db(":memory:");
    const RecordingImportResult r = import_recording(db, file(name), o);
    const auto samples = read_samples(db, r.run, 0, kImportDevice);
    EXPECT_EQ(r.samples, reference_->size());
    EXPECT_EQ(samples.size(), reference_->size()) << name;
    for (std::size_t i = 0; i < std::min(samples.size(), reference_->size()); ++i) {
      const auto& a = samples[i];
      const auto& b = (*reference_)[i];
      if (a.receive_time_s != b.receive_time_s || a.gyro_dps != b.gyro_dps ||
          a.accel_mps2 != b.accel_mps2 || a.device_time_s != b.device_time_s) {
        ADD_FAILURE() << name << ": sample " << i << " differs";
        break;
      }
    }
    return r;
  }

  static inline TempDir* dir_ = nullptr;
  static inline std::vector<core::ImuSample>* reference_ = nullptr;
};

// A recording the writers could not make (a Python module missing): skipped, or a failure when
// CALSTAND_REQUIRE_RECORDING_WRITERS is set (scripts/run-tests.sh, after setup-deps).
#define SKIP_UNLESS_WRITTEN(name, module)                                             \
  if (!std::filesystem::exists(file(name))) {                                         \
    if (std::getenv("CALSTAND_REQUIRE_RECORDING_WRITERS") != nullptr) {               \
      FAIL() << name << " was not written: " << module << " missing (setup-deps.sh)"; \
    }                                                                                 \
    GTEST_SKIP() << module << " missing";                                             \
  }

int runs(Database& db) { return db.sql().execAndGet("SELECT COUNT(*) FROM runs").getInt(); }

// The InputError of importing `path`, checking that nothing was written.
std::string refusal(const std::filesystem::path& path, RecordingImportOptions o = {}) {
  Database db(":memory:");
  try {
    import_recording(db, path, o);
  } catch (const core::InputError& e) {
    EXPECT_EQ(runs(db), 0);
    EXPECT_EQ(db.sql().execAndGet("SELECT COUNT(*) FROM sample_chunks").getInt(), 0);
    EXPECT_EQ(db.sql().execAndGet("SELECT COUNT(*) FROM steps").getInt(), 0);
    return e.what();
  }
  ADD_FAILURE() << "import of " << path << " succeeded";
  return "";
}

std::filesystem::path copy_cut(const std::filesystem::path& from, const std::filesystem::path& to,
                               std::uintmax_t keep) {
  std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing);
  std::filesystem::resize_file(to, keep);
  return to;
}

TEST_F(Recordings, DetectsEachFormatFromItsContent) {
  EXPECT_EQ(detect_recording_format(file("none.mcap")), "mcap");
  EXPECT_EQ(detect_recording_format(file("db3")), "ros2-bag");
  EXPECT_EQ(detect_recording_format(file("db3/bag_0.db3")), "ros2-bag");
  EXPECT_EQ(detect_recording_format(file("euroc")), "euroc");
  EXPECT_EQ(detect_recording_format(file("euroc/mav0")), "euroc");
  EXPECT_EQ(detect_recording_format(file("csv")), "calstand-import");
  EXPECT_EQ(detect_recording_format(file("csv/samples.csv")), std::nullopt);
  // A misleading extension does not matter.
  std::filesystem::copy_file(file("none.mcap"), file("renamed.bag"),
                             std::filesystem::copy_options::overwrite_existing);
  EXPECT_EQ(detect_recording_format(file("renamed.bag")), "mcap");
}

TEST_F(Recordings, McapZstdEqualsTheCsvImport) {
  SKIP_UNLESS_WRITTEN("zstd.mcap", "python3-zstandard");
  const auto r = expect_same_as_csv("zstd.mcap");
  EXPECT_EQ(r.format, "mcap");
  EXPECT_EQ(r.topic.name, "/imu/data");
  EXPECT_EQ(r.topic.type, "sensor_msgs/msg/Imu");
  EXPECT_EQ(r.topics.size(), 2u);  // /imu/data and /status, from the summary
}

TEST_F(Recordings, McapLz4EqualsTheCsvImport) {
  SKIP_UNLESS_WRITTEN("lz4.mcap", "python3-lz4");
  expect_same_as_csv("lz4.mcap");
}

TEST_F(Recordings, McapUncompressedWithAndWithoutSummaryEqualsTheCsvImport) {
  expect_same_as_csv("none.mcap");
  const auto r = expect_same_as_csv("nosummary.mcap");
  ASSERT_EQ(r.topics.size(), 2u);  // counted by reading the file
  EXPECT_EQ(r.topics[0].count, static_cast<std::uint64_t>(kSamples));
  EXPECT_NEAR(r.topics[0].rate_hz, 199.3, 1.0);
}

TEST_F(Recordings, McapRos1EncodingEqualsTheCsvImport) {
  const auto r = expect_same_as_csv("ros1.mcap");
  EXPECT_EQ(r.topic.type, "sensor_msgs/Imu");
  EXPECT_EQ(r.topic.encoding, "ros1");
}

TEST_F(Recordings, Ros2Db3EqualsTheCsvImport) {
  const auto r = expect_same_as_csv("db3");
  EXPECT_EQ(r.format, "ros2-bag");
  expect_same_as_csv("db3/bag_0.db3");
}

TEST_F(Recordings, Ros2BagWithMcapStorageInTwoFilesEqualsTheCsvImport) {
  const auto r = expect_same_as_csv("mcap_bag");
  EXPECT_EQ(r.format, "ros2-bag");
  EXPECT_EQ(r.topic.type, "sensor_msgs/msg/Imu");
  auto o = site();
  o.topic = "/status";
  EXPECT_CONTAINS(refusal(file("mcap_bag"), o), "not an IMU topic");
}

TEST_F(Recordings, Ros1BagsOfEachCompressionEqualTheCsvImport) {
  for (const char* name : {"none.bag", "bz2.bag", "lz4.bag"}) {
    SKIP_UNLESS_WRITTEN(name, "python3-rosbag");
    SCOPED_TRACE(name);
    const auto r = expect_same_as_csv(name);
    EXPECT_EQ(r.format, "ros1-bag");
    EXPECT_EQ(r.topic.type, "sensor_msgs/Imu");
  }
}

TEST_F(Recordings, EurocEqualsTheCsvImport) {
  auto o = site();
  o.topic = "/imu0";
  const auto r = expect_same_as_csv("euroc", o);
  EXPECT_EQ(r.format, "euroc");
  expect_same_as_csv("euroc/mav0");  // the only IMU: no --topic needed
}

TEST_F(Recordings, SummaryReportsGapsOutOfOrderStampsAndTheSite) {
  const auto r = expect_same_as_csv("none.mcap");
  // The gap, and the interval over the missing stamp of the out-of-order pair.
  EXPECT_EQ(r.gaps, 2u);
  EXPECT_NEAR(r.largest_gap_s, 0.042, 1e-4);
  EXPECT_EQ(r.out_of_order, 1u);
  EXPECT_EQ(r.duplicates, 0u);
  EXPECT_NEAR(r.rate_hz, 200.0, 0.5);
  EXPECT_EQ(r.site_source, "given");
  const auto j = r.to_json();
  EXPECT_EQ(j["gaps"]["count"], 2);
  EXPECT_EQ(j["out_of_order"], 1);
}

TEST_F(Recordings, TheRunIsAnImport2RunWithoutTable) {
  Database db(":memory:");
  const auto r = import_recording(db, file("none.mcap"), site());
  const auto meta = nlohmann::json::parse(
      db.sql()
          .execAndGet(fmt::format("SELECT station_snapshot FROM runs WHERE id = {}", r.run))
          .getString());
  EXPECT_EQ(meta["format"], "calstand-import/2");
  EXPECT_FALSE(meta.contains("table"));
  EXPECT_EQ(meta["site"]["gravity_mps2"], 9.8062);
  EXPECT_EQ(db.sql()
                .execAndGet(fmt::format("SELECT label FROM steps WHERE run_id = {}", r.run))
                .getString(),
            "recording");
  const auto means = read_step_means(db, r.run);
  ASSERT_EQ(means.size(), 1u);
}

TEST_F(Recordings, WithoutASiteTheDefaultIsUsedAndSaid) {
  Database db(":memory:");
  const auto r = import_recording(db, file("none.mcap"));
  EXPECT_EQ(r.latitude_deg, kDefaultLatitudeDeg);
  EXPECT_NEAR(r.gravity_mps2, 9.80620, 1e-4);
  EXPECT_NE(r.site_source.find("default"), std::string::npos) << r.site_source;
  RecordingImportOptions half;
  half.latitude_deg = 30.0;
  EXPECT_CONTAINS(refusal(file("none.mcap"), half), "--latitude and --height");
}

TEST_F(Recordings, SeveralImuTopicsAreListedAndOneIsChosenByTopic) {
  const std::string e = refusal(file("two_imu.mcap"));
  EXPECT_CONTAINS(e, "2 IMU topics");
  EXPECT_CONTAINS(e, "/imu/data (sensor_msgs/msg/Imu, 2000 messages");
  EXPECT_CONTAINS(e, "/imu2");
  EXPECT_CONTAINS(e, "Hz)");
  auto o = site();
  o.topic = "/imu/data";
  expect_same_as_csv("two_imu.mcap", o);
}

TEST_F(Recordings, ATopicThatIsNotAnImuOrAbsentIsRefused) {
  RecordingImportOptions o;
  o.topic = "/status";
  EXPECT_CONTAINS(refusal(file("none.mcap"), o), "topic /status is std_msgs/msg/String");
  EXPECT_CONTAINS(refusal(file("db3"), o), "not an IMU topic");
  EXPECT_CONTAINS(refusal(file("nosummary.mcap"), o), "not an IMU topic");
  o.topic = "/nothing";
  EXPECT_CONTAINS(refusal(file("none.mcap"), o), "no topic /nothing");
  EXPECT_CONTAINS(refusal(file("nosummary.mcap"), o), "no topic /nothing");
  EXPECT_CONTAINS(refusal(file("euroc"), o), "no topic /nothing");
}

TEST_F(Recordings, TruncatedFilesAreRefusedWithThePosition) {
  TempDir d;
  const auto size = std::filesystem::file_size(file("none.mcap"));
  const std::string e = refusal(copy_cut(file("none.mcap"), d.path() / "cut.mcap", size / 2));
  EXPECT_CONTAINS(e, "cut.mcap: byte");
  EXPECT_CONTAINS(e, "truncated");
  if (std::filesystem::exists(file("none.bag"))) {
    const auto bag = std::filesystem::file_size(file("none.bag"));
    const std::string b = refusal(copy_cut(file("none.bag"), d.path() / "cut.bag", bag / 2));
    EXPECT_CONTAINS(b, "cut.bag: byte");
    EXPECT_CONTAINS(b, "truncated");
  }
  const std::string db3 = refusal(copy_cut(file("db3/bag_0.db3"), d.path() / "cut.db3", 8192));
  EXPECT_CONTAINS(db3, "cut.db3");
}

TEST_F(Recordings, AChunkCrcMismatchIsRefused) {
  const std::string e = refusal(file("crc.mcap"));
  EXPECT_CONTAINS(e, "crc.mcap: byte");
  EXPECT_CONTAINS(e, "CRC mismatch");
}

TEST_F(Recordings, UnknownCompressionAndEncodingAreRefused) {
  TempDir d;
  // "zstd" -> "zstx" in the first chunk's compression field of an otherwise valid file.
  if (std::filesystem::exists(file("zstd.mcap"))) {
    std::string bytes = test::read(file("zstd.mcap"));
    const auto at = bytes.find("zstd");
    ASSERT_NE(at, std::string::npos);
    bytes[at + 3] = 'x';
    test::write(d.path() / "zstx.mcap", bytes);
    EXPECT_CONTAINS(refusal(d.path() / "zstx.mcap"), "unknown compression 'zstx'");
  }
  // The IMU channel's message encoding "cdr" -> "xdr": no IMU topic any more; asked for by
  // name, it is not an IMU topic.
  std::string bytes = test::read(file("none.mcap"));
  for (std::size_t at = bytes.find("\x03\0\0\0cdr", 0, 7); at != std::string::npos;
       at = bytes.find("\x03\0\0\0cdr", at + 1, 7)) {
    bytes[at + 4] = 'x';
  }
  test::write(d.path() / "xdr.mcap", bytes);
  EXPECT_CONTAINS(refusal(d.path() / "xdr.mcap"), "no IMU topic");
  RecordingImportOptions o;
  o.topic = "/imu/data";
  EXPECT_CONTAINS(refusal(d.path() / "xdr.mcap", o), "xdr encoding");
}

TEST_F(Recordings, EmptyAndForeignInputsAreRefused) {
  TempDir d;
  test::write(d.path() / "empty.mcap", "");
  EXPECT_CONTAINS(refusal(d.path() / "empty.mcap"), "not a recording");
  test::write(d.path() / "text.bag", "hello\n");
  EXPECT_CONTAINS(refusal(d.path() / "text.bag"), "not a recording");
  EXPECT_CONTAINS(refusal(d.path() / "missing.mcap"), "no such file");
  // An EuRoC file with a header and no rows.
  std::filesystem::create_directories(d.path() / "e" / "mav0" / "imu0");
  test::write(d.path() / "e" / "mav0" / "imu0" / "data.csv",
              "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
              "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n");
  EXPECT_CONTAINS(refusal(d.path() / "e"), "no messages on topic /imu0");
}

// export --format mcap: what this reader and the independent writer's file agree on comes back.
TEST_F(Recordings, AnExportedMcapImportsBackToTheSameSamples) {
  Database db(":memory:");
  const auto first = import_recording(db, file("none.mcap"), site());
  TempDir d;
  export_run_mcap(db, first.run, d.path() / "out.mcap");
  EXPECT_FALSE(std::filesystem::exists(d.path() / "out.mcap.part"));
  const auto again = import_recording(db, d.path() / "out.mcap", site());
  EXPECT_EQ(again.topic.name, "/imu/data");
  EXPECT_EQ(again.topic.type, "sensor_msgs/msg/Imu");
  const auto a = read_samples(db, first.run, 0, kImportDevice);
  const auto b = read_samples(db, again.run, 0, kImportDevice);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    // Seconds to sec + nanosec and back: within a nanosecond and a double's resolution at
    // 1.7e9 s; rad/s and back: within rounding.
    ASSERT_NEAR(a[i].receive_time_s, b[i].receive_time_s, 5e-7) << i;
    ASSERT_EQ(a[i].accel_mps2, b[i].accel_mps2) << i;
    for (int k = 0; k < 3; ++k) ASSERT_NEAR(a[i].gyro_dps[k], b[i].gyro_dps[k], 1e-13) << i;
  }
  EXPECT_EQ(again.out_of_order, first.out_of_order);
  EXPECT_EQ(again.gaps, first.gaps);
}

// Damaged files of every binary format (random bytes changed, or cut at a random place) are
// imported or refused with an InputError: never another exception, a crash or a hang.
TEST_F(Recordings, DamagedFilesAreImportedOrRefusedNeverWorse) {
  TempDir d;
  std::mt19937 rng(20261205);
  int refused = 0;
  int imported = 0;
  for (const char* name : {"none.mcap", "zstd.mcap", "lz4.mcap", "nosummary.mcap", "ros1.mcap",
                           "none.bag", "bz2.bag", "lz4.bag"}) {
    if (!std::filesystem::exists(file(name))) continue;
    const std::string original = test::read(file(name));
    for (int trial = 0; trial < 60; ++trial) {
      std::string bytes = original;
      if (trial % 4 == 3) {
        bytes.resize(std::uniform_int_distribution<std::size_t>(0, bytes.size() - 1)(rng));
      } else {
        // Mostly in the first kilobytes, where the headers, schemas and lengths are.
        const std::size_t span =
            trial % 2 == 0 ? std::min<std::size_t>(bytes.size(), 2048) : bytes.size();
        for (int k = 0; k < 1 + trial % 3; ++k) {
          bytes[std::uniform_int_distribution<std::size_t>(0, span - 1)(rng)] =
              static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
        }
      }
      const auto path = d.path() / (std::string("damaged-") + name);
      test::write(path, bytes);
      Database db(":memory:");
      try {
        RecordingImportOptions o = site();
        o.topic = "/imu/data";
        import_recording(db, path, o);
        ++imported;
      } catch (const core::InputError&) {
        ++refused;
        EXPECT_EQ(runs(db), 0) << name << " trial " << trial;
      } catch (const std::exception& e) {
        ADD_FAILURE() << name << " trial " << trial << ": " << e.what();
      }
    }
  }
  EXPECT_GT(refused, 0);
  std::cout << refused << " damaged files refused, " << imported << " imported\n";
}

TEST_F(Recordings, ReadsInBatchesOfBoundedSize) {
  auto reader = open_recording(file("none.mcap"));
  reader->select("/imu/data");
  std::vector<ImuRecord> batch;
  std::size_t total = 0;
  std::size_t batches = 0;
  while (reader->read(batch, 256)) {
    EXPECT_LE(batch.size(), 256u);
    total += batch.size();
    ++batches;
  }
  EXPECT_EQ(total, static_cast<std::size_t>(kSamples));
  EXPECT_GE(batches, static_cast<std::size_t>(kSamples / 256));
  EXPECT_DOUBLE_EQ(reader->progress(), 1.0);
}

}  // namespace
}  // namespace calstand::store

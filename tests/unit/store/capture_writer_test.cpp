#include "store/capture_writer.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "store/error.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"
#include "temp_dir.hpp"

namespace calstand::store {
namespace {

using testing::TempDir;

core::ImuSample sample(std::uint32_t i, double offset = 0.0) {
  core::ImuSample s;
  s.receive_time_s = 100.0 + 0.001 * i;
  s.device_time_s = 0.001 * i;
  s.sequence = i;
  s.gyro_dps = {offset + 0.01 * (i % 7), -0.02, 0.5};
  s.accel_mps2 = {0.001, 0.002, 9.79 + 1e-4 * (i % 3)};
  s.temperature_c = 25.0 + 0.001 * (i % 11);
  return s;
}

/// A database file with one run of `steps` pending capture steps.
struct Fixture {
  TempDir dir;
  std::string path = dir.file("capture.db");
  Database db{path};
  RunStore runs{db};
  std::int64_t run = 0;
  std::vector<std::int64_t> step_ids;

  explicit Fixture(int steps = 2) {
    NewRun r;
    r.procedure_name = "test";
    run = runs.create_run(r);
    std::vector<NewStep> s;
    for (int i = 0; i < steps; ++i) s.push_back({"capture", "c", {}, "steps[0]"});
    step_ids = runs.add_steps(run, s);
  }
};

TEST(CaptureWriter, EverySampleArrivesInOrderPerDevice) {
  Fixture f;
  CaptureWriterOptions options;
  options.chunk.max_samples = 500;  // several chunks per stream
  const std::uint32_t n = 5000;
  {
    CaptureWriter w(f.path, options);
    const auto a = w.open_stream(f.run, f.step_ids[0], 1, "imu0");
    const auto b = w.open_stream(f.run, f.step_ids[0], 1, "imu1");
    EXPECT_EQ(w.open_stream(f.run, f.step_ids[0], 1, "imu0"), a);
    for (std::uint32_t i = 0; i < n; ++i) {
      ASSERT_TRUE(w.push(a, sample(i)));
      ASSERT_TRUE(w.push(b, sample(i, 1.0)));
    }
    const StepCommit c = w.commit_step(f.step_ids[0], 1);
    EXPECT_EQ(c.samples, 2u * n);
    EXPECT_EQ(c.chunks, 2u * 10u);
    EXPECT_EQ(c.dropped, 0u);
    EXPECT_EQ(w.counters().pushed, 2u * n);
    EXPECT_EQ(w.counters().written, 2u * n);
    EXPECT_EQ(w.counters().commits, 1u);
  }
  f.runs.mark_step_completed(f.run, 0, 1, {1.0, "t"});
  const auto got = read_samples(f.db, f.run, 0, "imu1");
  ASSERT_EQ(got.size(), n);
  for (std::uint32_t i = 0; i < n; ++i) {
    ASSERT_EQ(got[i].sequence, i);
    ASSERT_NEAR(got[i].gyro_dps.x(), 1.0 + 0.01 * (i % 7), 1e-6);
  }
  EXPECT_EQ(read_samples(f.db, f.run, 0, "imu0").size(), n);
  EXPECT_EQ(sample_devices(f.db, f.run), (std::vector<std::string>{"imu0", "imu1"}));
}

TEST(CaptureWriter, CommitStepIsVisibleToAnotherConnectionWithStepMeans) {
  Fixture f;
  CaptureWriter w(f.path);
  const auto s = w.open_stream(f.run, f.step_ids[1], 3, "imu0");
  std::vector<core::ImuSample> batch;
  for (std::uint32_t i = 0; i < 1000; ++i) batch.push_back(sample(i));
  ASSERT_TRUE(w.push(s, batch));
  w.commit_step(f.step_ids[1], 3);

  // A fresh connection (as after a crash) sees the samples and their means.
  Database other(f.path);
  RunStore(other).mark_step_completed(f.run, 1, 3, {2.0, "t"});
  EXPECT_EQ(read_samples(other, f.run, 1, "imu0").size(), 1000u);
  const auto means = read_step_means(other, f.run);
  ASSERT_EQ(means.size(), 1u);
  EXPECT_EQ(means[0].step_index, 1u);
  EXPECT_EQ(means[0].attempt, 3);
  EXPECT_EQ(means[0].count, 1000);
  double gx = 0.0;
  double az = 0.0;
  for (const auto& x : batch) {
    gx += x.gyro_dps.x();
    az += x.accel_mps2.z();
  }
  EXPECT_NEAR(means[0].gyro_dps.x(), gx / 1000.0, 1e-12);
  EXPECT_NEAR(means[0].accel_mps2.z(), az / 1000.0, 1e-12);
  EXPECT_GT(means[0].gyro_std_dps.x(), 0.0);
  EXPECT_EQ(means[0].gyro_std_dps.y(), 0.0);
  EXPECT_EQ(means[0].first_receive_time_s, batch.front().receive_time_s);
  EXPECT_EQ(means[0].last_receive_time_s, batch.back().receive_time_s);
  EXPECT_EQ(other.sql().execAndGet("PRAGMA integrity_check").getString(), "ok");
}

TEST(CaptureWriter, QueueHighWaterIsTheLargestBacklogAndOutlivesTheFlush) {
  Fixture f;
  CaptureWriterOptions options;
  options.queue_capacity = 5000;
  CaptureWriter w(f.path, options);
  EXPECT_EQ(w.counters().queue_high_water, 0u);
  const auto s = w.open_stream(f.run, f.step_ids[0], 1, "imu0");
  std::vector<core::ImuSample> batch;
  for (std::uint32_t i = 0; i < 1200; ++i) batch.push_back(sample(i));
  // One push of 1200 puts at least 1200 in the queue at once, whatever the writer has taken.
  ASSERT_TRUE(w.push(s, batch));
  w.flush();
  EXPECT_GE(w.counters().queue_high_water, 1200u);
  // Smaller pushes later do not lower it, and a refused push does not raise it.
  ASSERT_TRUE(w.push(s, std::span(batch).first(10)));
  std::vector<core::ImuSample> too_many(6000, sample(0));
  EXPECT_FALSE(w.push(s, too_many));
  w.commit_step(f.step_ids[0], 1);
  EXPECT_GE(w.counters().queue_high_water, 1200u);
  EXPECT_LE(w.counters().queue_high_water, 1210u);
}

TEST(CaptureWriter, OverflowIsRefusedCountedAndRecordedAsAFaultEvent) {
  Fixture f;
  std::atomic<std::uint64_t> reported{0};
  CaptureWriterOptions options;
  options.queue_capacity = 100;
  options.on_overflow = [&](const OverflowReport& r) { reported += r.dropped; };
  CaptureWriter w(f.path, options);
  const auto s = w.open_stream(f.run, f.step_ids[0], 1, "imu0");
  std::vector<core::ImuSample> too_many;
  for (std::uint32_t i = 0; i < 101; ++i) too_many.push_back(sample(i));
  EXPECT_FALSE(w.push(s, too_many));  // more than the capacity: never fits
  EXPECT_TRUE(w.push(s, std::span(too_many).first(10)));
  const StepCommit c = w.commit_step(f.step_ids[0], 1);
  EXPECT_EQ(c.samples, 10u);
  EXPECT_EQ(c.dropped, 101u);
  EXPECT_EQ(w.counters().dropped_queue_full, 101u);
  w.flush();
  EXPECT_EQ(w.counters().overflow_events, 1u);
  EXPECT_EQ(reported.load(), 101u);

  const auto events = f.runs.load_run(f.run).events;
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, EventKind::kFault);
  EXPECT_EQ(events[0].source, "capture_writer");
  EXPECT_NE(events[0].message.find("101 samples of imu0 dropped"), std::string::npos)
      << events[0].message;
  EXPECT_EQ(events[0].detail["dropped"], 101);
  EXPECT_EQ(events[0].time_s, too_many[0].receive_time_s);
}

TEST(CaptureWriter, DiscardAttemptDropsQueuedAndStoredSamples) {
  Fixture f;
  CaptureWriterOptions options;
  options.chunk.max_samples = 100;
  CaptureWriter w(f.path, options);
  const auto first = w.open_stream(f.run, f.step_ids[0], 1, "imu0");
  for (std::uint32_t i = 0; i < 550; ++i) ASSERT_TRUE(w.push(first, sample(i)));
  w.flush();  // five full chunks stored, 50 samples pending
  EXPECT_EQ(f.db.sql().execAndGet("SELECT COUNT(*) FROM sample_chunks").getInt(), 5);
  w.discard_attempt(f.step_ids[0], 1);
  EXPECT_EQ(f.db.sql().execAndGet("SELECT COUNT(*) FROM sample_chunks").getInt(), 0);
  EXPECT_THROW(w.push(first, sample(0)), std::logic_error);

  // The repeat attempt is unaffected, and the same key may be opened again.
  const auto second = w.open_stream(f.run, f.step_ids[0], 2, "imu0");
  for (std::uint32_t i = 0; i < 30; ++i) ASSERT_TRUE(w.push(second, sample(i)));
  EXPECT_EQ(w.commit_step(f.step_ids[0], 2).samples, 30u);
  EXPECT_NO_THROW(w.open_stream(f.run, f.step_ids[0], 1, "imu0"));
  EXPECT_THROW(w.open_stream(f.run, f.step_ids[0], 2, "imu0"), std::logic_error);
  f.runs.mark_step_completed(f.run, 0, 2, {1.0, "t"});
  EXPECT_EQ(read_samples(f.db, f.run, 0, "imu0").size(), 30u);
}

TEST(CaptureWriter, ConcurrentProducersLoseNothing) {
  Fixture f(4);
  {
    CaptureWriter w(f.path);
    std::vector<std::thread> producers;
    for (int p = 0; p < 4; ++p) {
      producers.emplace_back([&, p] {
        const auto s = w.open_stream(f.run, f.step_ids[p], 1, "imu0");
        for (std::uint32_t i = 0; i < 20000; ++i) {
          while (!w.push(s, sample(i))) std::this_thread::yield();
        }
      });
    }
    for (auto& t : producers) t.join();
    for (int p = 0; p < 4; ++p) EXPECT_EQ(w.commit_step(f.step_ids[p], 1).samples, 20000u);
  }
  EXPECT_EQ(f.db.sql().execAndGet("SELECT SUM(count) FROM sample_chunks").getInt64(), 80000);
}

TEST(CaptureWriter, DestructorStoresPartialChunksOfOpenStreams) {
  Fixture f;
  {
    CaptureWriter w(f.path);
    const auto s = w.open_stream(f.run, f.step_ids[0], 1, "imu0");
    for (std::uint32_t i = 0; i < 77; ++i) ASSERT_TRUE(w.push(s, sample(i)));
  }
  Database other(f.path);
  EXPECT_EQ(read_samples(other, f.run, 0, "imu0").size(), 77u);
}

TEST(CaptureWriter, InMemoryDatabaseAndBadOptionsAreRefused) {
  EXPECT_THROW(CaptureWriter(":memory:"), StoreError);
  TempDir dir;
  EXPECT_THROW(CaptureWriter(dir.file("missing.db")), StoreError);  // not created by the writer
  Database db(dir.file("ok.db"));
  CaptureWriterOptions bad;
  bad.queue_capacity = 0;
  EXPECT_THROW(CaptureWriter(db.path(), bad), std::invalid_argument);
}

}  // namespace
}  // namespace calstand::store

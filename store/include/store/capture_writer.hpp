#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "core/imu_sample.hpp"
#include "store/sample_codec.hpp"

namespace calstand::store {

/// Samples refused because the queue was full, as recorded in table events (kind 'fault',
/// source 'capture_writer') and passed to CaptureWriterOptions::on_overflow.
struct OverflowReport {
  std::int64_t run_id = 0;
  std::int64_t step_id = 0;
  int attempt = 0;
  std::string device;
  std::uint64_t dropped = 0;          ///< samples refused since the previous report
  double first_dropped_time_s = 0.0;  ///< receive time of the first of them [s]
};

/// Options of CaptureWriter.
struct CaptureWriterOptions {
  std::size_t queue_capacity = 1u << 18;  ///< samples waiting for the writer thread, at most
  ChunkLimits chunk;                      ///< when chunks close
  SampleEncoding encoding = SampleEncoding::kCompact;
  int busy_timeout_ms = 10000;  ///< wait for other writers of the file [ms]
  /// Called on the writer thread after an overflow event is recorded; must not block long and
  /// must not call back into the writer.
  std::function<void(const OverflowReport&)> on_overflow;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// Named counters of a CaptureWriter (monotonic; read at any time).
struct CaptureWriterCounters {
  std::uint64_t pushed = 0;   ///< samples accepted by push()
  std::uint64_t written = 0;  ///< samples stored in chunks (inserted, maybe not committed)
  std::uint64_t chunks = 0;   ///< chunks inserted
  std::uint64_t dropped_queue_full = 0;  ///< samples refused by push() (queue full or failed)
  std::uint64_t overflow_events = 0;     ///< overflow events recorded
  std::uint64_t commits = 0;             ///< commit_step() calls completed
  /// Most samples ever waiting in the queue at once (the writer fell that far behind); set
  /// against queue_capacity it says how close the writer came to refusing samples.
  std::uint64_t queue_high_water = 0;
};

/// What commit_step() made durable for one step attempt (all its devices).
struct StepCommit {
  std::uint64_t samples = 0;  ///< samples stored for the attempt
  std::uint64_t chunks = 0;
  std::uint64_t dropped = 0;  ///< samples of the attempt refused by push() (queue full)
};

/// Stores IMU samples in chunks (sample_codec.hpp) from its own thread, so the engine's control
/// loop never waits for the disk.
///
/// Samples are pushed into a bounded queue for a stream = (run, step, attempt, device); the
/// writer thread encodes them into one chunk per stream, inserts full chunks in transactions
/// on its own connection, and on commit_step() stores the partial chunks and the step means
/// (table step_means) and makes everything of the step durable.
///
/// Overflow is never silent: push() returns false, counters().dropped_queue_full grows, and the
/// writer records a 'fault' event per stream and burst, then calls on_overflow.
///
/// Thread safety: every public method may be called from any thread. Destruction stores the
/// partial chunks of open streams (without step means), commits, and joins the thread.
class CaptureWriter {
 public:
  using StreamId = std::uint32_t;

  /// Opens its own connection to the database file at `db_path` (already migrated: open a
  /// Database first) and starts the thread. Throws StoreError when the file cannot be opened
  /// (an in-memory database cannot be shared and is refused), std::invalid_argument on bad
  /// options.
  explicit CaptureWriter(const std::string& db_path, CaptureWriterOptions options = {});
  ~CaptureWriter();
  CaptureWriter(const CaptureWriter&) = delete;
  CaptureWriter& operator=(const CaptureWriter&) = delete;

  /// The stream of one step attempt and device (the same id when called again for the same
  /// key). Throws std::logic_error when that stream was already committed.
  StreamId open_stream(std::int64_t run_id, std::int64_t step_id, int attempt,
                       const std::string& device);

  /// Queues one sample; false (and counted, and recorded as an event) when the queue is full
  /// or the writer has failed. Throws std::logic_error for an unknown or closed stream.
  bool push(StreamId stream, const core::ImuSample& sample);
  /// Queues all of `samples` or none (false as above).
  bool push(StreamId stream, std::span<const core::ImuSample> samples);

  /// Stores every sample queued so far for (step_id, attempt), its partial chunks and its step
  /// means, commits with a WAL sync (durable against power loss), closes its streams, and
  /// returns. Throws StoreError when the writer failed (the step is then not durable).
  StepCommit commit_step(std::int64_t step_id, int attempt);

  /// Drops the attempt: queued samples, partial chunks, stored chunks and step means; closes its
  /// streams (the same key may be opened again). Blocks until done; throws StoreError as above.
  void discard_attempt(std::int64_t step_id, int attempt);

  /// Blocks until every sample queued so far is inserted and committed (not WAL-synced).
  void flush();

  CaptureWriterCounters counters() const;
  std::size_t queue_capacity() const { return options_.queue_capacity; }

 private:
  struct Stream;
  /// Consecutive samples of one stream, as queued (pushes of one stream are merged).
  struct Batch {
    StreamId stream;
    std::vector<core::ImuSample> samples;
  };
  enum class CommandKind { kCommit, kDiscard, kFlush };
  struct Command;
  class Sink;

  StepCommit submit(CommandKind kind, std::int64_t step_id, int attempt);
  void close_streams(std::int64_t step_id, int attempt, bool forget);
  bool refuse(Stream& stream, std::size_t n, double first_time_s);  // caller holds mutex_
  Stream& stream_locked(StreamId id);
  void thread_main();
  void process(std::vector<Batch>& batches, std::uint64_t base,
               std::deque<std::unique_ptr<Command>>& commands);
  void execute(Command& command);
  void report_overflows();
  void refresh_streams();
  void append(Stream& s, const core::ImuSample& sample);

  CaptureWriterOptions options_;
  std::unique_ptr<Sink> sink_;  // the writer thread's connection and statements

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<Batch> queue_;    // guarded by mutex_
  std::size_t queued_ = 0;      // samples in queue_; guarded by mutex_
  std::uint64_t enqueued_ = 0;  // samples ever queued; guarded by mutex_
  bool sealed_ = false;         // a command follows queue_.back(): do not append to it; mutex_
  std::vector<std::vector<core::ImuSample>> spare_;  // emptied batch buffers for reuse; mutex_
  std::deque<std::unique_ptr<Command>> commands_;    // guarded by mutex_
  std::vector<std::unique_ptr<Stream>> streams_;     // guarded by mutex_ (elements are stable)
  std::map<std::tuple<std::int64_t, int, std::string>, StreamId> stream_index_;  // mutex_
  bool stop_ = false;              // guarded by mutex_
  bool overflow_pending_ = false;  // refusals not yet recorded; mutex_
  std::exception_ptr failure_;     // guarded by mutex_; set once by the thread

  std::vector<Stream*> local_streams_;  // writer thread only: snapshot of streams_

  std::atomic<std::uint64_t> pushed_{0}, written_{0}, chunks_{0}, dropped_{0}, overflow_events_{0},
      commits_{0}, high_water_{0};

  std::thread thread_;
};

}  // namespace calstand::store

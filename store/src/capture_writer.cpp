#include "store/capture_writer.hpp"

#include <SQLiteCpp/Database.h>
#include <SQLiteCpp/Statement.h>

#include <cmath>
#include <future>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "sql_util.hpp"
#include "step_stats.hpp"
#include "store/stamp.hpp"

namespace calstand::store {

using detail::guarded;

void CaptureWriterOptions::validate() const {
  if (queue_capacity == 0) throw std::invalid_argument("queue_capacity: must be > 0");
  if (chunk.max_samples == 0) throw std::invalid_argument("chunk.max_samples: must be > 0");
  if (!(chunk.max_span_s > 0.0)) throw std::invalid_argument("chunk.max_span_s: must be > 0");
  if (busy_timeout_ms < 0) throw std::invalid_argument("busy_timeout_ms: must be >= 0");
}

struct CaptureWriter::Stream {
  std::int64_t run_id = 0;
  std::int64_t step_id = 0;
  int attempt = 0;
  std::string device;
  // Guarded by mutex_.
  bool closed = false;
  std::uint64_t dropped = 0;           // refused by push(), total
  std::uint64_t dropped_reported = 0;  // of which already recorded as events
  double first_unreported_drop_s = 0.0;
  // Writer thread only. The encoder is allocated on the first sample and freed on close, so
  // thousands of finished streams cost no chunk buffers.
  std::optional<ChunkEncoder> encoder;
  StepStats stats;
  std::uint64_t written = 0;
  std::uint64_t chunks = 0;
};

struct CaptureWriter::Command {
  CommandKind kind;
  std::int64_t step_id = 0;
  int attempt = 0;
  std::uint64_t position = 0;  // queue items before this command
  std::promise<StepCommit> done;
};

/// The writer thread's connection: prepared statements and the open batch transaction.
class CaptureWriter::Sink {
 public:
  Sink(const std::string& path, int busy_timeout_ms)
      : db_(guarded("open " + path + " for capture", [&] {
          return SQLite::Database(path, SQLite::OPEN_READWRITE | SQLite::OPEN_URI, busy_timeout_ms);
        })) {
    guarded("prepare capture connection", [&] {
      const std::string file = db_.getFilename();
      if (file.empty()) {
        throw StoreError("open " + path + " for capture",
                         "an in-memory database cannot be shared with the writer thread");
      }
      // Same settings as store::Database (see the durability note there).
      db_.exec("PRAGMA journal_mode = WAL");
      db_.exec("PRAGMA synchronous = NORMAL");
      db_.exec("PRAGMA foreign_keys = ON");
      insert_chunk_.emplace(db_,
                            "INSERT INTO sample_chunks (run_id, step_id, attempt, device, "
                            "first_receive_time_s, last_receive_time_s, count, encoding, data) "
                            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)");
    });
  }

  ~Sink() {
    if (in_tx_) db_.tryExec("ROLLBACK");
  }

  void begin() {
    if (in_tx_) return;
    db_.exec("BEGIN IMMEDIATE");
    in_tx_ = true;
  }

  /// Commits the open batch transaction, if any (synchronous=NORMAL: no fsync).
  void commit() {
    if (!in_tx_) return;
    in_tx_ = false;
    db_.exec("COMMIT");
  }

  /// Runs `writes` in one transaction that is durable when this returns: the commit runs with
  /// synchronous=FULL, which fsyncs the WAL and so every earlier NORMAL commit too. The level
  /// may only change outside a transaction, hence the commit before.
  template <class F>
  void commit_durably(F&& writes) {
    commit();
    db_.exec("PRAGMA synchronous = FULL");
    std::forward<F>(writes)();
    if (in_tx_) {
      commit();
    } else {
      // Nothing new to write, but earlier NORMAL commits must still reach the disk: a
      // checkpoint syncs the WAL before copying it into the database.
      db_.exec("PRAGMA wal_checkpoint(PASSIVE)");
    }
    db_.exec("PRAGMA synchronous = NORMAL");
  }

  void insert_chunk(const Stream& s, const ChunkEncoder& enc) {
    begin();
    auto& st = *insert_chunk_;
    st.reset();
    st.bind(1, s.run_id);
    st.bind(2, s.step_id);
    st.bind(3, s.attempt);
    st.bindNoCopy(4, s.device);
    st.bind(5, enc.first_receive_time_s());
    st.bind(6, enc.last_receive_time_s());
    st.bind(7, static_cast<std::int64_t>(enc.count()));
    st.bind(8, static_cast<int>(enc.encoding()));
    const auto blob = enc.bytes();
    st.bindNoCopy(9, blob.data(), static_cast<int>(blob.size()));
    st.exec();
  }

  void insert_means(const Stream& s) {
    if (s.stats.count() == 0) return;
    begin();
    SQLite::Statement st(
        db_,
        "INSERT OR REPLACE INTO step_means (run_id, step_id, attempt, device, count, "
        "first_receive_time_s, last_receive_time_s, gx_dps, gy_dps, gz_dps, ax_mps2, ay_mps2, "
        "az_mps2, temperature_c, std_gx_dps, std_gy_dps, std_gz_dps, std_ax_mps2, std_ay_mps2, "
        "std_az_mps2, std_temperature_c) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, "
        "?, ?, ?, ?, ?)");
    st.bind(1, s.run_id);
    st.bind(2, s.step_id);
    st.bind(3, s.attempt);
    st.bind(4, s.device);
    st.bind(5, static_cast<std::int64_t>(s.stats.count()));
    st.bind(6, s.stats.first_time_s());
    st.bind(7, s.stats.last_time_s());
    for (int c = 0; c < StepStats::kChannels; ++c) {
      st.bind(8 + c, s.stats.mean(c));
      const double sd = s.stats.stddev(c);
      if (std::isfinite(sd)) {
        st.bind(15 + c, sd);
      } else {
        st.bind(15 + c);  // one sample: no spread
      }
    }
    st.exec();
  }

  void delete_attempt(std::int64_t step_id, int attempt) {
    begin();
    for (const char* sql : {"DELETE FROM sample_chunks WHERE step_id = ? AND attempt = ?",
                            "DELETE FROM step_means WHERE step_id = ? AND attempt = ?"}) {
      SQLite::Statement st(db_, sql);
      st.bind(1, step_id);
      st.bind(2, attempt);
      st.exec();
    }
  }

  void insert_overflow_event(const OverflowReport& r, std::size_t capacity) {
    begin();
    SQLite::Statement st(db_,
                         "INSERT INTO events (run_id, time_s, wall_utc, kind, source, message, "
                         "detail) VALUES (?, ?, ?, 'fault', 'capture_writer', ?, ?)");
    st.bind(1, r.run_id);
    st.bind(2, r.first_dropped_time_s);
    st.bind(3, utc_now_iso8601());
    st.bind(4, "capture queue full (capacity " + std::to_string(capacity) + " samples): " +
                   std::to_string(r.dropped) + " samples of " + r.device + " dropped (step id " +
                   std::to_string(r.step_id) + ", attempt " + std::to_string(r.attempt) + ")");
    st.bind(5, nlohmann::json{{"step_id", r.step_id},
                              {"attempt", r.attempt},
                              {"device", r.device},
                              {"dropped", r.dropped},
                              {"queue_capacity", capacity}}
                   .dump());
    st.exec();
  }

 private:
  SQLite::Database db_;
  std::optional<SQLite::Statement> insert_chunk_;
  bool in_tx_ = false;
};

CaptureWriter::CaptureWriter(const std::string& db_path, CaptureWriterOptions options)
    : options_(std::move(options)) {
  options_.validate();
  sink_ = std::make_unique<Sink>(db_path, options_.busy_timeout_ms);
  thread_ = std::thread([this] { thread_main(); });
}

CaptureWriter::~CaptureWriter() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

CaptureWriter::StreamId CaptureWriter::open_stream(std::int64_t run_id, std::int64_t step_id,
                                                   int attempt, const std::string& device) {
  std::lock_guard lock(mutex_);
  const auto key = std::make_tuple(step_id, attempt, device);
  if (auto it = stream_index_.find(key); it != stream_index_.end()) {
    if (streams_[it->second]->closed) {
      throw std::logic_error("CaptureWriter: stream of step id " + std::to_string(step_id) +
                             " attempt " + std::to_string(attempt) + " " + device +
                             " was already committed");
    }
    return it->second;
  }
  auto s = std::make_unique<Stream>();
  s->run_id = run_id;
  s->step_id = step_id;
  s->attempt = attempt;
  s->device = device;
  const auto id = static_cast<StreamId>(streams_.size());
  streams_.push_back(std::move(s));
  stream_index_.emplace(key, id);
  return id;
}

CaptureWriter::Stream& CaptureWriter::stream_locked(StreamId id) {
  if (id >= streams_.size()) throw std::logic_error("CaptureWriter: unknown stream id");
  Stream& s = *streams_[id];
  if (s.closed) {
    throw std::logic_error("CaptureWriter: push to closed stream (step id " +
                           std::to_string(s.step_id) + " attempt " + std::to_string(s.attempt) +
                           " " + s.device + ")");
  }
  return s;
}

bool CaptureWriter::refuse(Stream& s, std::size_t n, double first_time_s) {
  if (s.dropped == s.dropped_reported) s.first_unreported_drop_s = first_time_s;
  s.dropped += n;
  overflow_pending_ = true;
  dropped_.fetch_add(n, std::memory_order_relaxed);
  return false;
}

bool CaptureWriter::push(StreamId stream, const core::ImuSample& sample) {
  return push(stream, std::span<const core::ImuSample>(&sample, 1));
}

bool CaptureWriter::push(StreamId stream, std::span<const core::ImuSample> samples) {
  // Batches of one stream are merged up to this size, so single-sample pushes do not cost one
  // allocation each, while the writer still gets work in pieces it can interleave.
  static constexpr std::size_t kMaxBatch = 8192;
  if (samples.empty()) return true;
  bool accepted = false;
  bool wake = false;
  {
    std::lock_guard lock(mutex_);
    Stream& s = stream_locked(stream);
    if (failure_ || queued_ + samples.size() > options_.queue_capacity) {
      refuse(s, samples.size(), samples.front().receive_time_s);
      wake = true;  // so the thread records the overflow event
    } else {
      wake = queue_.empty();  // the thread only sleeps on an empty queue
      if (!queue_.empty() && !sealed_ && queue_.back().stream == stream &&
          queue_.back().samples.size() + samples.size() <= kMaxBatch) {
        auto& v = queue_.back().samples;
        v.insert(v.end(), samples.begin(), samples.end());
      } else {
        // Reusing buffers spares the page faults of fresh allocations at megasamples/s.
        std::vector<core::ImuSample> buffer;
        if (!spare_.empty()) {
          buffer = std::move(spare_.back());
          spare_.pop_back();
        }
        buffer.assign(samples.begin(), samples.end());
        queue_.push_back(Batch{stream, std::move(buffer)});
        sealed_ = false;
      }
      queued_ += samples.size();
      // Under mutex_, so a plain compare suffices; the atomic is for counters() readers.
      if (queued_ > high_water_.load(std::memory_order_relaxed)) {
        high_water_.store(queued_, std::memory_order_relaxed);
      }
      enqueued_ += samples.size();
      pushed_.fetch_add(samples.size(), std::memory_order_relaxed);
      accepted = true;
    }
  }
  if (wake) wake_.notify_one();
  return accepted;
}

void CaptureWriter::close_streams(std::int64_t step_id, int attempt, bool forget) {
  // Caller holds mutex_.
  for (auto it = stream_index_.lower_bound(std::make_tuple(step_id, attempt, std::string()));
       it != stream_index_.end() && std::get<0>(it->first) == step_id &&
       std::get<1>(it->first) == attempt;) {
    streams_[it->second]->closed = true;
    it = forget ? stream_index_.erase(it) : std::next(it);
  }
}

StepCommit CaptureWriter::submit(CommandKind kind, std::int64_t step_id, int attempt) {
  auto command = std::make_unique<Command>();
  command->kind = kind;
  command->step_id = step_id;
  command->attempt = attempt;
  auto done = command->done.get_future();
  {
    std::lock_guard lock(mutex_);
    if (failure_) std::rethrow_exception(failure_);
    if (kind != CommandKind::kFlush) close_streams(step_id, attempt, kind == CommandKind::kDiscard);
    command->position = enqueued_;
    sealed_ = true;  // later samples go after the command
    commands_.push_back(std::move(command));
  }
  wake_.notify_one();
  return done.get();  // rethrows the writer's StoreError
}

StepCommit CaptureWriter::commit_step(std::int64_t step_id, int attempt) {
  return submit(CommandKind::kCommit, step_id, attempt);
}

void CaptureWriter::discard_attempt(std::int64_t step_id, int attempt) {
  submit(CommandKind::kDiscard, step_id, attempt);
}

void CaptureWriter::flush() { submit(CommandKind::kFlush, 0, 0); }

CaptureWriterCounters CaptureWriter::counters() const {
  CaptureWriterCounters c;
  c.pushed = pushed_.load();
  c.written = written_.load();
  c.chunks = chunks_.load();
  c.dropped_queue_full = dropped_.load();
  c.overflow_events = overflow_events_.load();
  c.commits = commits_.load();
  c.queue_high_water = high_water_.load();
  return c;
}

// ---------------------------------------------------------------------------------------------
// Writer thread

void CaptureWriter::refresh_streams() {
  // Caller holds mutex_. Streams are only appended, so copying the new tail is enough.
  for (std::size_t i = local_streams_.size(); i < streams_.size(); ++i) {
    local_streams_.push_back(streams_[i].get());
  }
}

void CaptureWriter::append(Stream& s, const core::ImuSample& sample) {
  if (!s.encoder) s.encoder.emplace(options_.encoding, options_.chunk);
  ChunkEncoder& enc = *s.encoder;
  if (!enc.fits(sample)) {
    sink_->insert_chunk(s, enc);
    ++s.chunks;
    chunks_.fetch_add(1, std::memory_order_relaxed);
    written_.fetch_add(enc.count(), std::memory_order_relaxed);
    enc.clear();
  }
  enc.append(sample);
  s.stats.add(sample);
}

void CaptureWriter::execute(Command& c) {
  StepCommit result;
  auto writes = [&] {
    for (Stream* s : local_streams_) {
      if (s->step_id != c.step_id || s->attempt != c.attempt) continue;
      if (c.kind == CommandKind::kCommit) {
        if (s->encoder && !s->encoder->empty()) {
          sink_->insert_chunk(*s, *s->encoder);
          ++s->chunks;
          chunks_.fetch_add(1, std::memory_order_relaxed);
          written_.fetch_add(s->encoder->count(), std::memory_order_relaxed);
        }
        sink_->insert_means(*s);
        result.samples += s->stats.count();
        result.chunks += s->chunks;
        std::lock_guard lock(mutex_);
        result.dropped += s->dropped;
      }
      s->encoder.reset();
      s->stats = StepStats();
    }
    if (c.kind == CommandKind::kDiscard) sink_->delete_attempt(c.step_id, c.attempt);
  };
  if (c.kind == CommandKind::kCommit) {
    sink_->commit_durably(writes);
    commits_.fetch_add(1, std::memory_order_relaxed);
  } else {
    writes();
    sink_->commit();
  }
  c.done.set_value(result);
}

void CaptureWriter::report_overflows() {
  std::vector<OverflowReport> reports;
  {
    std::lock_guard lock(mutex_);
    if (!overflow_pending_) return;
    overflow_pending_ = false;
    for (Stream* s : local_streams_) {
      if (s->dropped == s->dropped_reported) continue;
      reports.push_back({s->run_id, s->step_id, s->attempt, s->device,
                         s->dropped - s->dropped_reported, s->first_unreported_drop_s});
      s->dropped_reported = s->dropped;
    }
  }
  if (reports.empty()) return;
  for (const auto& r : reports) sink_->insert_overflow_event(r, options_.queue_capacity);
  sink_->commit();
  overflow_events_.fetch_add(reports.size(), std::memory_order_relaxed);
  if (options_.on_overflow) {
    for (const auto& r : reports) options_.on_overflow(r);
  }
}

void CaptureWriter::process(std::vector<Batch>& batches, std::uint64_t base,
                            std::deque<std::unique_ptr<Command>>& commands) {
  // Commands sit between batches (push() never appends to a batch a command follows).
  auto next = commands.begin();
  std::uint64_t position = base;
  for (auto& b : batches) {
    for (; next != commands.end() && (*next)->position <= position; ++next) execute(**next);
    Stream& s = *local_streams_[b.stream];
    for (const auto& x : b.samples) append(s, x);
    position += b.samples.size();
  }
  for (; next != commands.end(); ++next) execute(**next);
}

void CaptureWriter::thread_main() {
  std::vector<Batch> batches;
  std::deque<std::unique_ptr<Command>> commands;
  std::uint64_t taken = 0;  // samples taken from the queue so far
  for (;;) {
    bool stopping = false;
    std::size_t taken_now = 0;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] {
        return stop_ || !queue_.empty() || !commands_.empty() || overflow_pending_;
      });
      // Hand the buffers of the previous round back for reuse (a bounded number).
      for (auto& b : batches) {
        if (spare_.size() >= 256) break;
        b.samples.clear();
        spare_.push_back(std::move(b.samples));
      }
      batches.clear();
      batches.swap(queue_);
      taken_now = queued_;
      queued_ = 0;
      commands.swap(commands_);
      refresh_streams();
      stopping = stop_;
    }
    const std::uint64_t base = taken;
    taken += taken_now;
    try {
      if (!failure_) {
        report_overflows();  // before commands, so commit_step() returns after the event
        process(batches, base, commands);
        report_overflows();
        sink_->commit();
        if (stopping) {
          // Keep what was captured, even of steps never committed; the engine discards
          // unfinished attempts on resume.
          sink_->commit_durably([&] {
            for (Stream* s : local_streams_) {
              if (s->encoder && !s->encoder->empty()) sink_->insert_chunk(*s, *s->encoder);
            }
          });
        }
      }
    } catch (...) {
      std::exception_ptr error = std::current_exception();
      try {
        throw;
      } catch (const SQLite::Exception& e) {
        error = std::make_exception_ptr(StoreError("capture writer", e.what()));
      } catch (...) {
      }
      std::lock_guard lock(mutex_);
      failure_ = error;
    }
    if (failure_) {
      for (auto& c : commands) {
        try {
          c->done.set_exception(failure_);
        } catch (const std::future_error&) {
          // already answered before the failure
        }
      }
    }
    commands.clear();
    if (stopping) break;
  }
}

}  // namespace calstand::store

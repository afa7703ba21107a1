#pragma once
// Private: reading batches on a thread of their own, a few ahead of the transaction that stores
// them (the streamed imports of recordings and of calstand-import folders).

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace calstand::store::detail {

/// Reads batches of `Record` from `Source` on a thread of its own, a few ahead of the caller, so
/// that reading, decompressing, parsing and decoding overlap with the database's writes; at
/// most kQueuedBatches batches wait (memory stays bounded). The source's exceptions come out of
/// next() after the batches read before them.
///
/// `Source` has `bool read(std::vector<Record>& batch, std::size_t max)` (false at the end) and
/// `double progress() const` (the fraction of the input consumed).
template <class Source, class Record>
class BatchPrefetch {
 public:
  static constexpr std::size_t kQueuedBatches = 4;

  BatchPrefetch(Source& source, std::size_t batch)
      : source_(source), batch_(batch), thread_([this] { run(); }) {}
  ~BatchPrefetch() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    changed_.notify_all();
    thread_.join();
  }
  BatchPrefetch(const BatchPrefetch&) = delete;
  BatchPrefetch& operator=(const BatchPrefetch&) = delete;

  /// The next batch into `out` with the fraction of the input read; false at the end (the
  /// thread is then done with the source).
  bool next(std::vector<Record>& out, double& progress) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return !queue_.empty() || done_; });
    if (queue_.empty()) {
      if (error_) std::rethrow_exception(error_);
      return false;
    }
    out.swap(queue_.front().first);
    progress = queue_.front().second;
    queue_.pop_front();
    changed_.notify_all();
    return true;
  }

 private:
  void run() {
    try {
      for (;;) {
        std::vector<Record> batch;
        batch.reserve(batch_);
        if (!source_.read(batch, batch_)) break;
        const double progress = source_.progress();
        std::unique_lock lock(mutex_);
        changed_.wait(lock, [&] { return queue_.size() < kQueuedBatches || stop_; });
        if (stop_) break;
        queue_.emplace_back(std::move(batch), progress);
        changed_.notify_all();
      }
    } catch (...) {
      std::lock_guard lock(mutex_);
      error_ = std::current_exception();
    }
    std::lock_guard lock(mutex_);
    done_ = true;
    changed_.notify_all();
  }

  Source& source_;
  std::size_t batch_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::pair<std::vector<Record>, double>> queue_;
  bool done_ = false;
  bool stop_ = false;
  std::exception_ptr error_;
  std::thread thread_;  // last: started once the members above exist
};

}  // namespace calstand::store::detail

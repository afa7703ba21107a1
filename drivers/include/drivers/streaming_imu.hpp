#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "core/clock.hpp"
#include "drivers/device_support.hpp"
#include "drivers/imu.hpp"
#include "drivers/sample_clock.hpp"

namespace calstand::drivers {

/// What every IMU streaming over a link shares, whatever the protocol (SerialImu, CanImu): a
/// reader thread that runs while the device is active, a bounded sample buffer drained by
/// poll(), fault counters and events, fault summaries at most once per second of station time,
/// and a lost link reopened with backoff. A subclass adds only its protocol: opening the link,
/// one read-and-decode step, its own counters and the wording of its fault summaries.
///
/// Public calls are made from one thread (the engine's); the reader thread is the only other.
/// A subclass's destructor must call stop_reader() first: the reader calls into the subclass.
class StreamingImu : public Imu {
 public:
  ~StreamingImu() override;
  StreamingImu(const StreamingImu&) = delete;
  StreamingImu& operator=(const StreamingImu&) = delete;

  const std::string& name() const override { return name_; }
  /// Stops the reader and opens the link (open_link()); kError with the link's reason if that
  /// throws, kInactive otherwise.
  Result configure() override;
  /// Starts the reader (refused when unconfigured). Samples that arrived before are dropped.
  Result activate() override;
  /// Stops the reader (the link stays open); the reader's last fault summary is queued first.
  Result deactivate() override;
  DeviceState state() const override { return life_.state(); }
  /// read_errors, reopens, buffer_overflows, the subclass's own and the protocol's counters.
  std::map<std::string, std::uint64_t> fault_counters() const override;
  std::vector<DeviceEvent> take_events() override { return events_.take(); }
  std::vector<core::ImuSample> poll() override;

 protected:
  /// The longest a read_step() may wait for data: deactivate() waits up to this for the reader.
  static constexpr std::chrono::milliseconds kReadTimeout{50};

  /// `extra_faults` are the subclass's counters, listed at zero before the first fault.
  StreamingImu(std::string name, core::Clock& clock,
               std::initializer_list<std::string_view> extra_faults = {});

  /// Opens the link (configure()). `after_error`: the device was in kError, so the link may be
  /// dead and wants closing first. Throws std::exception saying why it cannot be opened.
  virtual void open_link(bool after_error) = 0;
  /// Reopens a lost link (reader thread): true when it is back; false or an exception when it
  /// is still gone (retried with backoff while active).
  virtual bool reopen_link() = 0;
  /// One read from the link, waiting at most kReadTimeout so that deactivate() is noticed: decodes
  /// what came, stamps it (sample_clock()) and hands it to deliver(). A failure is a lost link
  /// (its message says why); the base then reopens it.
  virtual Result read_step() = 0;
  /// Queues an event for the faults seen since the last summary, `period_s` ago (reader
  /// thread). Called at most once per second, and once more when the reader stops.
  virtual void summarise_faults(double now_s, double period_s) = 0;
  /// Called before the reader starts (activate()): forget what belongs to the last run.
  virtual void on_reader_start() {}

  /// Appends samples for poll(); beyond 120 s of stream nobody polled, the oldest are dropped
  /// and counted (buffer_overflows). Reader thread.
  void deliver(const std::vector<core::ImuSample>& samples);
  /// Stamps `samples` with station time (sample_clock()) as they arrived at `arrival_s`; a
  /// device clock that jumped is counted (clock_restarts) and reported as an event. Reader
  /// thread.
  void stamp(std::vector<core::ImuSample>& samples, double arrival_s);
  /// Publishes the protocol decoder's counters for fault_counters() (they replace the last).
  void publish_protocol_counters(std::map<std::string, std::uint64_t> counters);
  /// Calls `attempt` until it returns true (true) or the reader is stopped (false), waiting
  /// 0.1 s after the first failure, doubling to 5 s, and noticing a stop within 10 ms. An
  /// exception from `attempt` counts as a failure.
  bool retry_with_backoff(const std::function<bool()>& attempt) const;
  /// Joins the reader thread, if running.
  void stop_reader();

  core::Clock& clock() const { return clock_; }
  FaultCounters& faults() { return faults_; }
  EventQueue& events() { return events_; }
  /// The reader thread's clock mapping; reset when it starts. Reader thread only.
  SampleClock& sample_clock() { return sample_clock_; }

 private:
  void read_loop();
  // A lost link: counted, an event and kError until it is back. false when stopped meanwhile.
  bool recover_link(const std::string& why);
  void summarise_faults_if_due(double now_s, bool force);

  std::string name_;
  core::Clock& clock_;
  Lifecycle life_;
  FaultCounters faults_;
  EventQueue events_;
  unsigned long clock_restarts_seen_ = 0;  // reader thread

  std::thread reader_;
  std::atomic<bool> running_{false};
  mutable std::mutex mutex_;  // guards buffer_ and protocol_counters_
  std::vector<core::ImuSample> buffer_;
  std::map<std::string, std::uint64_t> protocol_counters_;
  // Set before the reader starts, then reader thread only.
  std::size_t capacity_ = 0;
  SampleClock sample_clock_;
  double last_summary_s_ = 0.0;
};

}  // namespace calstand::drivers

#include "drivers/streaming_imu.hpp"

#include <algorithm>
#include <chrono>

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

// Faults are summarised in one event per this much station time [s].
constexpr double kFaultSummaryPeriodS = 1.0;
// The buffer holds this much stream when nobody polls, then drops the oldest [s].
constexpr double kBufferSpanS = 120.0;
// However slow the device, the buffer holds at least this many samples.
constexpr double kMinBufferSamples = 10000.0;
// Reopening a lost link: first wait, longest wait, and how often a stop is noticed meanwhile.
constexpr auto kFirstBackoff = 100ms;
constexpr auto kMaxBackoff = 5000ms;
constexpr auto kStopCheck = 10ms;

}  // namespace

StreamingImu::StreamingImu(std::string name, core::Clock& clock,
                           std::initializer_list<std::string_view> extra_faults)
    : name_(std::move(name)),
      clock_(clock),
      faults_{"read_errors", "reopens", "buffer_overflows", "clock_restarts"},
      sample_clock_(SampleClock::for_time_scale(clock.time_scale())) {
  for (auto n : extra_faults) faults_.set(n, 0);
}

// Too late for a reader still calling into the subclass (see the class comment); this only
// keeps a forgotten thread from terminating the program.
StreamingImu::~StreamingImu() { stop_reader(); }

Result StreamingImu::configure() {
  const bool after_error = life_.state() == DeviceState::kError;
  stop_reader();
  try {
    open_link(after_error);
  } catch (const std::exception& e) {
    life_.set(DeviceState::kError);
    return Result::failure(e.what());
  }
  life_.set(DeviceState::kInactive);
  return Result::success();
}

Result StreamingImu::activate() {
  if (auto r = life_.activate(); !r) return r;
  if (!running_) {
    {
      std::lock_guard lock(mutex_);
      buffer_.clear();  // what arrived before activation belongs to nobody
    }
    capacity_ =
        static_cast<std::size_t>(std::max(kMinBufferSamples, kBufferSpanS * sample_rate_hz()));
    sample_clock_.reset();
    last_summary_s_ = clock_.now_s();
    on_reader_start();
    running_ = true;
    reader_ = std::thread([this] { read_loop(); });
  }
  return Result::success();
}

Result StreamingImu::deactivate() {
  stop_reader();
  life_.deactivate();
  return Result::success();
}

void StreamingImu::stop_reader() {
  running_ = false;
  if (reader_.joinable()) reader_.join();
}

std::vector<core::ImuSample> StreamingImu::poll() {
  std::vector<core::ImuSample> out;
  std::lock_guard lock(mutex_);
  out.swap(buffer_);
  return out;
}

std::map<std::string, std::uint64_t> StreamingImu::fault_counters() const {
  auto out = faults_.snapshot();
  std::lock_guard lock(mutex_);
  for (const auto& [k, v] : protocol_counters_) out[k] = v;
  return out;
}

void StreamingImu::stamp(std::vector<core::ImuSample>& samples, double arrival_s) {
  for (auto& s : samples) s.receive_time_s = sample_clock_.stamp(s.device_time_s, arrival_s);
  if (const auto restarts = sample_clock_.restarts(); restarts != clock_restarts_seen_) {
    clock_restarts_seen_ = restarts;
    faults_.set("clock_restarts", restarts);
    events_.push(arrival_s, true,
                 "device clock jumped: time stamps re-anchored to the arrival times");
  }
}

void StreamingImu::deliver(const std::vector<core::ImuSample>& samples) {
  std::lock_guard lock(mutex_);
  buffer_.insert(buffer_.end(), samples.begin(), samples.end());
  if (buffer_.size() > capacity_) {
    // Nobody is draining: keep the newest, say how many went.
    const auto excess = buffer_.size() - capacity_;
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(excess));
    faults_.add("buffer_overflows", excess);
  }
}

void StreamingImu::publish_protocol_counters(std::map<std::string, std::uint64_t> counters) {
  std::lock_guard lock(mutex_);
  protocol_counters_ = std::move(counters);
}

void StreamingImu::read_loop() {
  while (running_) {
    const Result r = read_step();
    if (!r) {
      if (!recover_link(r.message)) break;  // deactivated while waiting
      continue;
    }
    summarise_faults_if_due(clock_.now_s(), false);
  }
  summarise_faults_if_due(clock_.now_s(), true);
}

bool StreamingImu::recover_link(const std::string& why) {
  faults_.add("read_errors");
  events_.push(clock_.now_s(), true, "link lost: " + why);
  life_.set(DeviceState::kError);
  if (!retry_with_backoff([this] { return reopen_link(); })) return false;
  faults_.add("reopens");
  events_.push(clock_.now_s(), false, "link back");
  life_.set(DeviceState::kActive);
  return true;
}

bool StreamingImu::retry_with_backoff(const std::function<bool()>& attempt) const {
  // A replugged adapter comes back under the same name, but not at once: retry while active,
  // ever less often so that a link gone for good costs nothing.
  std::chrono::milliseconds backoff = kFirstBackoff;
  while (running_) {
    try {
      if (attempt()) return true;
    } catch (const std::exception&) {
      // still gone; wait and retry
    }
    for (auto waited = 0ms; waited < backoff && running_; waited += kStopCheck) {
      std::this_thread::sleep_for(kStopCheck);
    }
    backoff = std::min(backoff * 2, std::chrono::milliseconds(kMaxBackoff));
  }
  return false;
}

void StreamingImu::summarise_faults_if_due(double now_s, bool force) {
  if (!force && now_s - last_summary_s_ < kFaultSummaryPeriodS) return;
  summarise_faults(now_s, now_s - last_summary_s_);
  last_summary_s_ = now_s;
}

}  // namespace calstand::drivers

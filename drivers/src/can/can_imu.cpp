#include "drivers/can_imu.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>

#include "drivers/socketcan_port.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

// The reader wakes at least this often to notice deactivate() [ms].
constexpr auto kReadTimeout = 50ms;
// Faults are summarised in one event per this much station time [s].
constexpr double kFaultReportPeriodS = 1.0;
// The buffer holds this much stream when nobody polls, then drops the oldest [s].
constexpr double kBufferSpanS = 120.0;
// A kernel stamp older than this at read time is not trusted (clock set, suspend) [s].
constexpr double kMaxKernelAgeS = 1.0;

// The counters worth an event when they grow (the others count good traffic).
constexpr std::array kReportedFaults = {"unknown_ids",      "bad_frames",    "bad_dlc",
                                        "duplicate_frames", "late_frames",   "incomplete_samples",
                                        "invalid_samples",  "sequence_gaps", "malformed_messages",
                                        "buffer_overflows"};

double realtime_now_s() {
  const auto t = std::chrono::system_clock::now().time_since_epoch();
  return std::chrono::duration<double>(t).count();
}

}  // namespace

CanImu::CanImu(const core::ImuConfig& config, core::Clock& clock, const std::string& where,
               const std::string& base_dir)
    : CanImu(config.name, CanImuConnection::from_json(config.connection, where, base_dir), nullptr,
             clock) {}

CanImu::CanImu(std::string name, CanImuConnection connection,
               std::unique_ptr<CanTransport> transport, core::Clock& clock)
    : name_(std::move(name)),
      clock_(clock),
      connection_(std::move(connection)),
      transport_(transport ? std::move(transport)
                           : std::make_unique<SocketCanPort>(connection_.interface)),
      assembler_(connection_.map, connection_.sequence_modulus, connection_.sample_rate_hz) {}

CanImu::~CanImu() {
  stop_reader();
  transport_->close();
}

void CanImu::open_transport() {
  const std::vector<canid_t> ids =
      connection_.filter_ids ? connection_.map.ids() : std::vector<canid_t>{};
  transport_->set_filters(ids);
  transport_->open();
}

Result CanImu::configure() {
  const bool was_in_error = life_.state() == DeviceState::kError;
  stop_reader();
  try {
    // After a failure the socket may be dead: start afresh. Otherwise keep it (configuring
    // twice must not drop a healthy link, and a socket pair cannot be reopened).
    if (was_in_error) transport_->close();
    open_transport();
  } catch (const std::exception& e) {
    life_.set(DeviceState::kError);
    return Result::failure(e.what());
  }
  assembler_.reset();  // a fresh start: partial samples from before belong to nobody
  life_.set(DeviceState::kInactive);
  return Result::success();
}

Result CanImu::activate() {
  if (life_.state() == DeviceState::kError) {
    // The reader may still be retrying a lost link: only configure() starts afresh.
    return Result::failure("in error: configure it again first");
  }
  if (auto r = life_.activate(); !r) return r;
  if (!running_) {
    {
      std::lock_guard lock(mutex_);
      buffer_.clear();  // what arrived before activation belongs to nobody
    }
    sample_clock_.reset();
    last_arrival_s_ = -1e300;
    last_report_s_ = clock_.now_s();
    running_ = true;
    reader_ = std::thread([this] { read_loop(); });
  }
  return Result::success();
}

Result CanImu::deactivate() {
  stop_reader();
  life_.deactivate();
  return Result::success();
}

void CanImu::stop_reader() {
  running_ = false;
  if (reader_.joinable()) reader_.join();
}

std::vector<core::ImuSample> CanImu::poll() {
  std::vector<core::ImuSample> out;
  std::lock_guard lock(mutex_);
  out.swap(buffer_);
  return out;
}

std::map<std::string, std::uint64_t> CanImu::fault_counters() const {
  auto out = faults_.snapshot();
  std::lock_guard lock(mutex_);
  for (const auto& [k, v] : assembler_counters_) out[k] = v;
  return out;
}

double CanImu::arrival_time_s(const ReceivedCanFrame& frame) const {
  const double now_s = clock_.now_s();
  // The kernel stamps frames on the wall clock; the station clock is another clock. Their
  // difference is not needed: only the frame's age at read time, taken from the wall clock
  // now, moves to the station clock. A virtual clock has no relation to the wall clock. With
  // an accelerated station clock (time_scale > 1) the age stays in wall seconds: a few ms at
  // most, well within what SampleClock's minimum-delay estimate absorbs.
  if (!connection_.kernel_timestamps || !frame.kernel_time_s || clock_.is_virtual()) return now_s;
  const double age_s = realtime_now_s() - *frame.kernel_time_s;
  if (age_s < 0.0 || age_s > kMaxKernelAgeS) return now_s;
  return now_s - age_s;
}

void CanImu::read_loop() {
  using Status = CanReadResult::Status;
  std::vector<core::ImuSample> decoded;
  const auto capacity =
      static_cast<std::size_t>(std::max(10000.0, kBufferSpanS * connection_.sample_rate_hz));
  while (running_) {
    const CanReadResult r = transport_->read(kReadTimeout);
    decoded.clear();
    if (r.status == Status::kError) {
      faults_.add("read_errors");
      events_.push(clock_.now_s(), true, "link lost: " + r.message);
      life_.set(DeviceState::kError);
      if (!reopen()) break;  // deactivated while waiting
      events_.push(clock_.now_s(), false, "link back");
      life_.set(DeviceState::kActive);
      continue;
    }
    if (r.status == Status::kMalformed) faults_.add("malformed_messages");
    if (r.status == Status::kFrame) {
      // SampleClock needs arrivals in order; kernel stamps mapped through two clocks read a
      // few us apart can step back by that much, so hold them monotonic.
      const double arrival_s = std::max(arrival_time_s(r.frame), last_arrival_s_);
      last_arrival_s_ = arrival_s;
      // A sample is stamped with the arrival of the frame that completed it.
      assembler_.feed(r.frame.frame, decoded);
      for (auto& s : decoded) {
        s.receive_time_s = sample_clock_.stamp(s.device_time_s, arrival_s);
      }
      faults_.set("clock_restarts", sample_clock_.restarts());
    }
    {
      std::lock_guard lock(mutex_);
      buffer_.insert(buffer_.end(), decoded.begin(), decoded.end());
      if (buffer_.size() > capacity) {
        // Nobody is draining: keep the newest, say how many went.
        const auto excess = buffer_.size() - capacity;
        buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(excess));
        faults_.add("buffer_overflows", excess);
      }
      if (r.status == Status::kFrame) assembler_counters_ = assembler_.counters();
    }
    report_faults(clock_.now_s(), false);
  }
  report_faults(clock_.now_s(), true);
}

void CanImu::report_faults(double now_s, bool force) {
  if (!force && now_s - last_report_s_ < kFaultReportPeriodS) return;
  const auto now = fault_counters();
  std::string summary;
  for (const char* key : kReportedFaults) {
    const auto it = now.find(key);
    const std::uint64_t total = it == now.end() ? 0 : it->second;
    const std::uint64_t delta = total - reported_[key];
    if (delta > 0)
      summary += fmt::format("{}{} {} (total {})", summary.empty() ? "" : ", ", delta, key, total);
    reported_[key] = total;
  }
  if (!summary.empty()) {
    events_.push(
        now_s, true,
        fmt::format("CAN faults in the last {:.1f} s: {}", now_s - last_report_s_, summary));
  }
  last_report_s_ = now_s;
}

bool CanImu::reopen() {
  // An interface taken down and up again (or a replugged USB adapter) comes back under the
  // same name: retry with backoff while active.
  auto backoff = 100ms;
  while (running_) {
    try {
      transport_->close();
      open_transport();
      faults_.add("reopens");
      return true;
    } catch (const std::exception&) {
      // still gone; wait and retry
    }
    for (auto waited = 0ms; waited < backoff && running_; waited += 10ms) {
      std::this_thread::sleep_for(10ms);
    }
    backoff = std::min(backoff * 2, std::chrono::milliseconds(5000));
  }
  return false;
}

std::unique_ptr<Imu> make_can_imu(const core::ImuConfig& config, core::Clock& clock,
                                  std::string where, const std::string& base_dir) {
  return std::make_unique<CanImu>(config, clock, where, base_dir);
}

}  // namespace calstand::drivers

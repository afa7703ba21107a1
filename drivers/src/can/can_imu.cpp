#include "drivers/can_imu.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>

#include "drivers/socketcan_port.hpp"

namespace calstand::drivers {
namespace {

// A kernel stamp older than this at read time is not trusted (clock set, suspend) [s].
constexpr double kMaxKernelAgeS = 1.0;

// The counters worth an event when they grow (the others count good traffic).
constexpr std::array kReportedFaults = {"unknown_ids",      "bad_frames",      "bad_dlc",
                                        "duplicate_frames", "late_frames",     "incomplete_samples",
                                        "invalid_samples",  "sequence_gaps",   "malformed_messages",
                                        "counter_errors",   "buffer_overflows"};

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
    : StreamingImu(std::move(name), clock, {"malformed_messages", "clock_restarts"}),
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

void CanImu::open_link(bool after_error) {
  // After a failure the socket may be dead: start afresh. Otherwise keep it (configuring
  // twice must not drop a healthy link, and a socket pair cannot be reopened).
  if (after_error) transport_->close();
  open_transport();
  assembler_.reset();  // a fresh start: partial samples from before belong to nobody
}

bool CanImu::reopen_link() {
  // An interface taken down and up again comes back under the same name.
  transport_->close();
  open_transport();
  return true;
}

Result CanImu::activate() {
  if (state() == DeviceState::kError) {
    // The reader may still be retrying a lost link: only configure() starts afresh.
    return Result::failure("in error: configure it again first");
  }
  Result r = StreamingImu::activate();
  std::string absent;
  for (std::size_t i = 0; i < kImuSignalCount; ++i) {
    if (connection_.map.absent[i])
      absent +=
          fmt::format("{}{}", absent.empty() ? "" : ", ", signal_name(static_cast<ImuSignal>(i)));
  }
  // A fit over all six axes cannot use a NaN axis: say so where the operator looks.
  if (r.ok && !absent.empty()) {
    events().push(clock().now_s(), false,
                  "not measured by this device, delivered as NaN: " + absent);
  }
  return r;
}

double CanImu::arrival_time_s(const ReceivedCanFrame& frame) const {
  const double now_s = clock().now_s();
  // The kernel stamps frames on the wall clock; the station clock is another clock. Their
  // difference is not needed: only the frame's age at read time, taken from the wall clock
  // now, moves to the station clock. A virtual clock has no relation to the wall clock. With
  // an accelerated station clock (time_scale > 1) the age stays in wall seconds: a few ms at
  // most, well within what SampleClock's minimum-delay estimate absorbs.
  if (!connection_.kernel_timestamps || !frame.kernel_time_s || clock().is_virtual()) {
    return now_s;
  }
  const double age_s = realtime_now_s() - *frame.kernel_time_s;
  if (age_s < 0.0 || age_s > kMaxKernelAgeS) return now_s;
  return now_s - age_s;
}

Result CanImu::read_step() {
  using Status = CanReadResult::Status;
  const CanReadResult r = transport_->read(kReadTimeout);
  if (r.status == Status::kError) return Result::failure(r.message);
  if (r.status == Status::kMalformed) faults().add("malformed_messages");
  if (r.status != Status::kFrame) return Result::success();
  // SampleClock needs arrivals in order; kernel stamps mapped through two clocks read a
  // few us apart can step back by that much, so hold them monotonic.
  const double arrival_s = std::max(arrival_time_s(r.frame), last_arrival_s_);
  last_arrival_s_ = arrival_s;
  // A sample is stamped with the arrival of the frame that completed it.
  decoded_.clear();
  assembler_.feed(r.frame.frame, decoded_);
  stamp(decoded_, arrival_s);
  deliver(decoded_);
  for (const std::string& fault : assembler_.take_device_faults())
    events().push(clock().now_s(), true, "device fault: " + fault);
  publish_protocol_counters(assembler_.counters());
  return Result::success();
}

void CanImu::summarise_faults(double now_s, double period_s) {
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
    events().push(now_s, true,
                  fmt::format("CAN faults in the last {:.1f} s: {}", period_s, summary));
  }
}

std::unique_ptr<Imu> make_can_imu(const core::ImuConfig& config, core::Clock& clock,
                                  std::string where, const std::string& base_dir) {
  return std::make_unique<CanImu>(config, clock, where, base_dir);
}

}  // namespace calstand::drivers

#include "drivers/frame_hunt.hpp"

namespace calstand::drivers {

void FrameHunt::append(std::span<const std::uint8_t> bytes) {
  counters_.bytes_fed += bytes.size();
  // Compact before appending, and only then: the buffer never holds more than one partial
  // frame plus the new bytes, however long the stream runs, and discard()/consume() stay O(1).
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(start_));
  start_ = 0;
  buffer_.insert(buffer_.end(), bytes.begin(), bytes.end());
}

void FrameHunt::discard(std::size_t count) {
  start_ += count;
  if (quiet_) {
    // Still the tail of a frame cut by the input flush: not a fault of the line.
    counters_.start_bytes += count;
    return;
  }
  if (!hunting_) ++counters_.resyncs;
  hunting_ = true;
  counters_.garbage_bytes += count;
}

void FrameHunt::consume(std::size_t count) {
  pass(count);
  quiet_ = false;
}

void FrameHunt::pass(std::size_t count) {
  start_ += count;
  hunting_ = false;
}

void FrameHunt::restart() {
  counters_.start_bytes += buffered();
  buffer_.clear();
  start_ = 0;
  quiet_ = true;
  hunting_ = false;
}

void copy_hunt_counters(const FrameHunt& hunt, std::map<std::string, std::uint64_t>& stats) {
  const FrameHunt::Counters& c = hunt.counters();
  stats["bytes_fed"] = c.bytes_fed;
  stats["garbage_bytes"] = c.garbage_bytes;
  stats["resyncs"] = c.resyncs;
  stats["start_bytes"] = c.start_bytes;
}

}  // namespace calstand::drivers

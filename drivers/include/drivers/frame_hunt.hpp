#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

namespace calstand::drivers {

/// The byte accounting every serial IMU frame decoder shares: the bytes that are not yet a
/// frame, and where each byte fed went. A decoder appends what it read, looks at bytes(), and
/// for each candidate either waits for more, discard()s bytes while hunting for a frame, or
/// consume()s a frame it accepted. Invariant: bytes_fed == the bytes consumed + garbage_bytes +
/// start_bytes + buffered() (+ what restart(kUncounted) dropped).
class FrameHunt {
 public:
  /// Where every byte fed went. The decoders publish these under the same names.
  struct Counters {
    std::uint64_t bytes_fed = 0;      ///< bytes given to append() [bytes]
    std::uint64_t garbage_bytes = 0;  ///< discarded while hunting for a frame [bytes]
    std::uint64_t resyncs = 0;        ///< runs of discarded bytes (each loss of frame lock)
    std::uint64_t start_bytes = 0;    ///< discarded while quiet(), after restart() [bytes]
  };

  /// What restart() does with the bytes still buffered.
  /// Adds `bytes` after the unconsumed ones and counts them in bytes_fed.
  void append(std::span<const std::uint8_t> bytes);

  /// The bytes not yet discarded or consumed, oldest first. Valid until the next append().
  std::span<const std::uint8_t> bytes() const {
    return {buffer_.data() + start_, buffer_.size() - start_};
  }
  /// Bytes held back waiting for the rest of a frame [bytes].
  std::size_t buffered() const { return buffer_.size() - start_; }

  /// Drops the first `count` bytes (count <= buffered()) as not a frame: garbage while the
  /// stream is locked or hunting (a new run counts one resync), start bytes while quiet().
  void discard(std::size_t count);
  /// Hunts: when the first byte cannot start a frame (`starts_frame` rejects it), discards it
  /// and every byte up to the next one `starts_frame` accepts (all of them when none does) and
  /// returns true; otherwise discards nothing and returns false. One call discards a whole run
  /// of garbage (one resync), so a decoder calls it before looking at a candidate.
  template <class StartsFrame>
  bool discard_until(StartsFrame starts_frame) {
    const std::span<const std::uint8_t> rest = bytes();
    if (rest.empty() || starts_frame(rest[0])) return false;
    const auto next = std::find_if(rest.begin() + 1, rest.end(), starts_frame);
    discard(static_cast<std::size_t>(next - rest.begin()));
    return true;
  }
  /// Takes the first `count` bytes (count <= buffered()) as a good frame: the hunt is over and
  /// the quiet state after restart() ends.
  void consume(std::size_t count);
  /// Takes the first `count` bytes (count <= buffered()) as valid but not proof of frame lock
  /// (a terminator, a start-up message): the hunt is over, the quiet state stays.
  void pass(std::size_t count);

  /// The reader (re)starts after the line's input flush: what the buffer holds and the bytes
  /// before the next consume() are the tail of a frame cut by the flush (or a frame the
  /// restart abandons): start bytes, not garbage, so that every byte fed stays counted.
  void restart();

  /// True from restart() to the next consume(): a decoder counts no checksum or length errors
  /// then, since a candidate cut by the flush is not a fault of the line.
  bool quiet() const { return quiet_; }

  /// Since construction; restart() does not reset them.
  const Counters& counters() const { return counters_; }

 private:
  std::vector<std::uint8_t> buffer_;
  std::size_t start_ = 0;  // first unconsumed byte in buffer_ (compacted lazily, in append())
  bool hunting_ = false;   // discarding bytes since the last good frame
  bool quiet_ = false;     // after restart(): bytes before the first good frame are start bytes
  Counters counters_;
};

/// Copies `hunt`'s counters into a decoder's own counters struct, whose fields of the same
/// names are part of its public interface (stats()).
template <class Stats>
void copy_hunt_counters(const FrameHunt& hunt, Stats& stats) {
  const FrameHunt::Counters& c = hunt.counters();
  stats.bytes_fed = c.bytes_fed;
  stats.garbage_bytes = c.garbage_bytes;
  stats.resyncs = c.resyncs;
  stats.start_bytes = c.start_bytes;
}

/// The counters every frame decoder publishes under these names (FrameDecoder::counters()),
/// read from its counters struct: FrameHunt's four and frames, crc_errors, length_errors and
/// sequence_gaps. A decoder adds its own to the map.
template <class Stats>
std::map<std::string, std::uint64_t> frame_decoder_counters(const Stats& stats) {
  return {{"bytes_fed", stats.bytes_fed},         {"frames", stats.frames},
          {"crc_errors", stats.crc_errors},       {"length_errors", stats.length_errors},
          {"garbage_bytes", stats.garbage_bytes}, {"resyncs", stats.resyncs},
          {"sequence_gaps", stats.sequence_gaps}, {"start_bytes", stats.start_bytes}};
}

/// The same for a decoder that keeps its counters by name (those of FrameHunt::Counters).
void copy_hunt_counters(const FrameHunt& hunt, std::map<std::string, std::uint64_t>& stats);

}  // namespace calstand::drivers

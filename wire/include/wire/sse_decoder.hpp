#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "wire/sse_event.hpp"

namespace calstand::wire {

/// Reads a server-sent event stream by the WHATWG HTML parsing rules ("server-sent events",
/// interpreting an event stream), fed in whatever pieces the connection delivers: a piece may
/// end anywhere, between a CR and its LF too. Lines end at LF, CR or CRLF; a BOM at the very
/// start is dropped; lines starting with ':' are comments; `field: value` and `field:value`
/// are the same (one leading space is dropped); several `data:` lines are joined with "\n";
/// an event without `event:` is a "message"; `id:` sets the last event id, kept for later
/// events, unless it holds NUL; `retry:` with digits only sets the reconnection time; other
/// fields are ignored, and so is an event without data. An event is dispatched at the blank
/// line that ends it; what the stream holds after the last blank line is no event.
/// Not thread-safe: one reader feeds it.
class SseDecoder {
 public:
  /// Called for each event; returns false to stop reading (feed() then returns false too).
  using Handler = std::function<bool(const SseEvent&)>;

  explicit SseDecoder(Handler on_event);

  /// Takes the next piece of the stream; false once the handler asked to stop (the rest of
  /// the piece is dropped, and later pieces are ignored).
  bool feed(std::string_view piece);

  /// The last event id the stream set (empty before any `id:`): what a reader that reconnects
  /// sends as Last-Event-ID.
  const std::string& last_event_id() const { return last_event_id_; }
  /// The reconnection time the stream asked for with `retry:` [ms], if it did.
  std::optional<std::uint64_t> retry_ms() const { return retry_ms_; }

 private:
  bool consume(std::string_view bytes);
  void take_line();
  void dispatch();

  Handler on_event_;
  bool stopped_ = false;
  bool at_stream_start_ = true;  // a BOM is dropped here only
  std::string bom_prefix_;       // the first bytes while they may still be a BOM
  bool after_cr_ = false;        // the previous line ended at CR: an LF next belongs to it
  std::string line_;
  std::string type_buffer_;
  std::string data_buffer_;
  std::string id_buffer_;
  std::string last_event_id_;
  std::optional<std::uint64_t> retry_ms_;
};

}  // namespace calstand::wire

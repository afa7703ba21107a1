#pragma once

#include <string>

namespace calstand::wire {

/// One server-sent event (WHATWG HTML, "server-sent events"), as written and as read.
struct SseEvent {
  /// The `event:` field; a reader sees "message" for an event that had none.
  std::string type = "message";
  /// The `data:` lines joined with "\n" (one line of JSON text in calstandd's stream).
  std::string data;
  /// Written: the `id:` field, none when empty. Read: the stream's last event id when the event
  /// was dispatched, which stays set from an earlier event when this one carried no `id:`
  /// (what a reconnecting reader sends as `Last-Event-ID`).
  std::string id;
};

}  // namespace calstand::wire

#pragma once

#include <functional>
#include <string>
#include <string_view>

namespace calstand::daemon::api {

/// One server-sent event as calstandd sends them (schemas/api.md): `id` (empty for the
/// greeting and gap messages), `type` (the `event:` field) and `data` (one line of JSON text).
struct SseMessage {
  std::string id;
  std::string type;
  std::string data;
};

/// Splits a server-sent event stream, fed in whatever pieces the connection delivers, into
/// messages. Comment lines (keep-alives) and messages without a type are skipped.
class SseParser {
 public:
  /// `on_message` returns false to stop: feed() then returns false too.
  explicit SseParser(std::function<bool(const SseMessage&)> on_message) : on_message_(std::move(on_message)) {}

  /// Takes the next piece of the stream; false once `on_message` asked to stop.
  bool feed(std::string_view piece);

 private:
  std::function<bool(const SseMessage&)> on_message_;
  std::string buffer_;
};

}  // namespace calstand::daemon::api

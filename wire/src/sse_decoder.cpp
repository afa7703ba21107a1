#include "wire/sse_decoder.hpp"

#include <algorithm>
#include <charconv>
#include <utility>

namespace calstand::wire {
namespace {

constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";

bool all_ascii_digits(std::string_view text) {
  return !text.empty() &&
         std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
}

}  // namespace

SseDecoder::SseDecoder(Handler on_event) : on_event_(std::move(on_event)) {}

bool SseDecoder::feed(std::string_view piece) {
  if (stopped_) return false;
  if (at_stream_start_) {
    // The BOM may arrive a byte at a time: hold the first bytes while they could be one.
    while (!piece.empty() && bom_prefix_.size() < kByteOrderMark.size() &&
           kByteOrderMark.starts_with(bom_prefix_)) {
      bom_prefix_ += piece.front();
      piece.remove_prefix(1);
    }
    const bool could_be_bom = kByteOrderMark.starts_with(bom_prefix_);
    if (could_be_bom && bom_prefix_.size() < kByteOrderMark.size()) return true;  // need more
    at_stream_start_ = false;
    const std::string held = std::exchange(bom_prefix_, {});
    if (!could_be_bom && !consume(held)) return false;
  }
  return consume(piece);
}

bool SseDecoder::consume(std::string_view bytes) {
  while (!bytes.empty()) {
    if (after_cr_) {
      after_cr_ = false;
      if (bytes.front() == '\n') {
        bytes.remove_prefix(1);
        continue;
      }
    }
    const std::size_t eol = bytes.find_first_of("\r\n");
    if (eol == std::string_view::npos) {
      line_.append(bytes);
      return true;
    }
    line_.append(bytes.substr(0, eol));
    after_cr_ = bytes[eol] == '\r';
    bytes.remove_prefix(eol + 1);
    take_line();
    if (stopped_) return false;
  }
  return true;
}

void SseDecoder::take_line() {
  const std::string line = std::exchange(line_, {});
  if (line.empty()) {
    dispatch();
    return;
  }
  if (line.front() == ':') return;  // a comment
  const std::size_t colon = line.find(':');
  const std::string_view field = std::string_view(line).substr(0, colon);
  std::string_view value;
  if (colon != std::string::npos) {
    value = std::string_view(line).substr(colon + 1);
    if (value.starts_with(' ')) value.remove_prefix(1);
  }
  if (field == "event") {
    type_buffer_ = value;
  } else if (field == "data") {
    data_buffer_.append(value);
    data_buffer_ += '\n';
  } else if (field == "id") {
    if (value.find('\0') == std::string_view::npos) id_buffer_ = value;
  } else if (field == "retry") {
    std::uint64_t ms = 0;
    const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), ms);
    // Digits only; a number too large for 64 bits is ignored like any other bad value.
    if (all_ascii_digits(value) && ec == std::errc() && end == value.data() + value.size())
      retry_ms_ = ms;
  }
}

void SseDecoder::dispatch() {
  last_event_id_ = id_buffer_;
  if (data_buffer_.empty()) {
    type_buffer_.clear();
    return;
  }
  data_buffer_.pop_back();  // the "\n" after the last data line
  SseEvent event;
  event.type = type_buffer_.empty() ? "message" : std::move(type_buffer_);
  event.data = std::move(data_buffer_);
  event.id = last_event_id_;
  type_buffer_.clear();
  data_buffer_.clear();
  if (!on_event_(event)) stopped_ = true;
}

}  // namespace calstand::wire

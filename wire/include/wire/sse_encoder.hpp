#pragma once

#include <string>
#include <string_view>

#include "wire/sse_event.hpp"

namespace calstand::wire {

/// The text of one event: `id:` (when `event.id` is not empty), `event:` (when the type is
/// not empty), one `data:` line per line of `event.data` (split at LF, CR and CRLF, which a
/// reader joins again with "\n"), and the blank line that ends it. Throws
/// std::invalid_argument when the id or the type holds a line break or NUL: no field could
/// carry it.
std::string encode_sse_event(const SseEvent& event);

/// A comment (`: TEXT` and a blank line): readers ignore it; it keeps an idle connection
/// alive and shows the server that a reader has gone. Line breaks in `text` become spaces.
std::string encode_sse_comment(std::string_view text);

/// `retry: MS`: how long a standard reader waits before reconnecting [ms].
std::string encode_sse_retry(unsigned retry_ms);

}  // namespace calstand::wire

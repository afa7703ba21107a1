#pragma once
// The events an SSE stream gives, for the decoder's and the encoder's tests.

#include <gtest/gtest.h>

#include <cstddef>
#include <string_view>
#include <vector>

#include "wire/sse_decoder.hpp"

namespace calstand::wire::test {

/// Every event a whole stream gives, fed in pieces of `piece` bytes (0: all at once).
inline std::vector<SseEvent> decode(std::string_view stream, std::size_t piece = 0) {
  std::vector<SseEvent> events;
  SseDecoder decoder([&](const SseEvent& e) {
    events.push_back(e);
    return true;
  });
  if (piece == 0) piece = stream.size() + 1;
  for (std::size_t at = 0; at < stream.size(); at += piece) {
    EXPECT_TRUE(decoder.feed(stream.substr(at, piece)));
  }
  return events;
}

}  // namespace calstand::wire::test

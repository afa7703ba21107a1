#include "daemon/api/sse_parser.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace {

using calstand::daemon::api::SseMessage;
using calstand::daemon::api::SseParser;

const std::string kStream =
    "event: station\ndata: {\"name\":\"s\"}\n\n"
    ": keep-alive\n\n"
    "id: 17-3\nevent: step\ndata: {\"step\":1}\n\n"
    "id: 17-4\nevent: run\ndata: {\"state\":\"completed\"}\n\n";

TEST(SseParser, SplitsMessagesHoweverTheStreamIsCut) {
  for (std::size_t piece = 1; piece <= kStream.size(); ++piece) {
    std::vector<SseMessage> got;
    SseParser parser([&](const SseMessage& m) {
      got.push_back(m);
      return true;
    });
    for (std::size_t at = 0; at < kStream.size(); at += piece) {
      ASSERT_TRUE(parser.feed(std::string_view(kStream).substr(at, piece)));
    }
    ASSERT_EQ(got.size(), 3u) << "pieces of " << piece;  // the keep-alive is no message
    EXPECT_EQ(got[0].type, "station");
    EXPECT_TRUE(got[0].id.empty());
    EXPECT_EQ(got[1].id, "17-3");
    EXPECT_EQ(got[1].data, "{\"step\":1}");
    EXPECT_EQ(got[2].type, "run");
    EXPECT_EQ(got[2].id, "17-4");
  }
}

TEST(SseParser, StopsWhenTheReaderSaysSo) {
  int seen = 0;
  SseParser parser([&](const SseMessage&) { return ++seen < 2; });
  EXPECT_FALSE(parser.feed(kStream));
  EXPECT_EQ(seen, 2);
}

}  // namespace

#include "wire/sse_decoder.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sse_events.hpp"

namespace {

using calstand::wire::SseDecoder;
using calstand::wire::SseEvent;
using calstand::wire::test::decode;

TEST(SseDecoder, OneLeadingSpaceOfAValueIsDropped) {
  const auto events = decode("data:a\n\ndata: b\n\ndata:  c\n\nevent:x\ndata\n\n");
  ASSERT_EQ(events.size(), 4u);
  EXPECT_EQ(events[0].data, "a");
  EXPECT_EQ(events[1].data, "b");
  EXPECT_EQ(events[2].data, " c");  // only one space goes
  EXPECT_EQ(events[3].type, "x");   // a field without a colon has the empty value
  EXPECT_EQ(events[3].data, "");
}

TEST(SseDecoder, DataLinesAreJoinedWithLineFeeds) {
  const auto events = decode("data: one\ndata: two\ndata:\ndata: four\n\n");
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].data, "one\ntwo\n\nfour");
}

TEST(SseDecoder, AnEventWithoutATypeIsAMessage) {
  const auto events = decode("data: a\n\nevent: step\ndata: b\n\ndata: c\n\n");
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].type, "message");
  EXPECT_EQ(events[1].type, "step");
  EXPECT_EQ(events[2].type, "message");  // the type does not carry over
}

TEST(SseDecoder, TheLastEventIdIsKeptForLaterEvents) {
  std::vector<std::string> ids;
  SseDecoder d([&](const SseEvent& e) {
    ids.push_back(e.id);
    return true;
  });
  EXPECT_EQ(d.last_event_id(), "");
  ASSERT_TRUE(d.feed("data: a\n\nid: 7-1\ndata: b\n\ndata: c\n\nid\ndata: d\n\n"));
  EXPECT_EQ(ids, (std::vector<std::string>{"", "7-1", "7-1", ""}));  // `id` alone clears it
  EXPECT_EQ(d.last_event_id(), "");
  ASSERT_TRUE(d.feed("id: 7-9\n\n"));  // an id without data still sets it
  EXPECT_EQ(d.last_event_id(), "7-9");
}

TEST(SseDecoder, AnIdHoldingNulIsIgnored) {
  std::vector<std::string> ids;
  SseDecoder d([&](const SseEvent& e) {
    ids.push_back(e.id);
    return true;
  });
  ASSERT_TRUE(d.feed("id: 1\ndata: a\n\n"));
  ASSERT_TRUE(d.feed(std::string_view("id: 2\0x\ndata: b\n\n", 18)));
  EXPECT_EQ(ids, (std::vector<std::string>{"1", "1"}));
}

TEST(SseDecoder, RetryTakesDigitsOnly) {
  SseDecoder d([](const SseEvent&) { return true; });
  EXPECT_FALSE(d.retry_ms().has_value());
  ASSERT_TRUE(d.feed("retry: 2500\n\n"));
  EXPECT_EQ(d.retry_ms(), 2500u);
  ASSERT_TRUE(d.feed("retry: 12x\n\nretry: -5\n\nretry:\n\nretry: 99999999999999999999999\n\n"));
  EXPECT_EQ(d.retry_ms(), 2500u);
  ASSERT_TRUE(d.feed("retry:300\n\n"));
  EXPECT_EQ(d.retry_ms(), 300u);
}

TEST(SseDecoder, CommentsAndUnknownFieldsAreIgnored) {
  const auto events = decode(": keep-alive\n\n:\ndata: a\n: in between\nfoo: bar\ndata: b\n\n");
  ASSERT_EQ(events.size(), 1u);  // a comment alone dispatches nothing
  EXPECT_EQ(events[0].data, "a\nb");
}

TEST(SseDecoder, AnEventWithoutDataIsNotDispatched) {
  const auto events = decode("event: lonely\n\ndata: x\n\n");
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].type, "message");  // the lonely type was dropped with its event
}

TEST(SseDecoder, LinesEndAtLfCrOrCrLf) {
  for (const std::string_view eol : {"\n", "\r", "\r\n"}) {
    std::string stream;
    for (const char* line : {"id: 3", "event: run", "data: a", "data: b", ""}) {
      stream.append(line).append(eol);
    }
    const auto events = decode(stream);
    ASSERT_EQ(events.size(), 1u) << "line ending "
                                 << (eol == "\n"   ? "LF"
                                     : eol == "\r" ? "CR"
                                                   : "CRLF");
    EXPECT_EQ(events[0].type, "run");
    EXPECT_EQ(events[0].data, "a\nb");
    EXPECT_EQ(events[0].id, "3");
  }
  // Mixed in one stream; CR CR is two line ends (a blank line), CR LF only one.
  const auto mixed = decode("data: a\r\ndata: b\rdata: c\n\r\ndata: d\r\r");
  ASSERT_EQ(mixed.size(), 2u);
  EXPECT_EQ(mixed[0].data, "a\nb\nc");
  EXPECT_EQ(mixed[1].data, "d");
}

// Every split of the stream into two pieces and into pieces of every size gives the same
// events: between CR and LF too, and inside the BOM.
TEST(SseDecoder, ThePiecesTheStreamArrivesInDoNotMatter) {
  const std::string stream =
      "\xEF\xBB\xBF"
      "event: station\r\ndata: {\"name\":\"s\"}\r\n\r\n"
      ": keep-alive\r\n\r\n"
      "id: 17-3\revent: step\rdata: {\"step\":1}\r\r"
      "id: 17-4\nevent: run\ndata: {\"state\":\"completed\"}\n\n";
  const auto whole = decode(stream);
  ASSERT_EQ(whole.size(), 3u);
  EXPECT_EQ(whole[0].type, "station");
  EXPECT_EQ(whole[0].id, "");
  EXPECT_EQ(whole[1].id, "17-3");
  EXPECT_EQ(whole[1].data, "{\"step\":1}");
  EXPECT_EQ(whole[2].type, "run");
  EXPECT_EQ(whole[2].id, "17-4");
  const auto same = [&](const std::vector<SseEvent>& got) {
    if (got.size() != whole.size()) return false;
    for (std::size_t i = 0; i < got.size(); ++i) {
      if (got[i].type != whole[i].type || got[i].data != whole[i].data ||
          got[i].id != whole[i].id) {
        return false;
      }
    }
    return true;
  };
  for (std::size_t piece = 1; piece <= stream.size(); ++piece) {
    EXPECT_TRUE(same(decode(stream, piece))) << "pieces of " << piece;
  }
  for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
    std::vector<SseEvent> got;
    SseDecoder d([&](const SseEvent& e) {
      got.push_back(e);
      return true;
    });
    ASSERT_TRUE(d.feed(std::string_view(stream).substr(0, cut)));
    ASSERT_TRUE(d.feed(std::string_view(stream).substr(cut)));
    EXPECT_TRUE(same(got)) << "cut at " << cut;
  }
}

TEST(SseDecoder, ALfAfterACrInTheNextPieceEndsNoSecondLine) {
  std::vector<SseEvent> got;
  SseDecoder d([&](const SseEvent& e) {
    got.push_back(e);
    return true;
  });
  ASSERT_TRUE(d.feed("data: a\r"));
  ASSERT_TRUE(d.feed("\ndata: b\r"));
  EXPECT_TRUE(got.empty());  // CR LF was one line end, not the blank line
  ASSERT_TRUE(d.feed("\n\r\n"));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].data, "a\nb");
}

TEST(SseDecoder, OnlyABomAtTheStartOfTheStreamIsDropped) {
  const std::string bom = "\xEF\xBB\xBF";
  const auto events = decode(bom + "data: a\n\n" + bom + "data: b\n\n");
  ASSERT_EQ(events.size(), 1u);  // the second BOM begins a field named BOM "data", unknown
  EXPECT_EQ(events[0].data, "a");
  EXPECT_EQ(decode(bom + bom + "data: a\n\n").size(), 0u);
  // Bytes that only begin like a BOM are kept: the first line's field is not "data".
  const auto almost = decode(bom.substr(0, 1) + "data: x\n\ndata: y\n\n", 1);
  ASSERT_EQ(almost.size(), 1u);
  EXPECT_EQ(almost[0].data, "y");
}

TEST(SseDecoder, WhatFollowsTheLastBlankLineIsNoEvent) {
  EXPECT_TRUE(decode("data: a\n").empty());
  EXPECT_TRUE(decode("data: a").empty());
}

TEST(SseDecoder, StopsWhenTheReaderSaysSo) {
  int seen = 0;
  SseDecoder d([&](const SseEvent&) { return ++seen < 2; });
  EXPECT_FALSE(d.feed("data: 1\n\ndata: 2\n\ndata: 3\n\n"));
  EXPECT_EQ(seen, 2);
  EXPECT_FALSE(d.feed("data: 4\n\n"));
  EXPECT_EQ(seen, 2);
}

}  // namespace

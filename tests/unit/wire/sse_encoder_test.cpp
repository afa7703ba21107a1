#include "wire/sse_encoder.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "sse_events.hpp"
#include "wire/sse_decoder.hpp"

namespace {

using calstand::wire::encode_sse_comment;
using calstand::wire::encode_sse_event;
using calstand::wire::encode_sse_retry;
using calstand::wire::SseDecoder;
using calstand::wire::SseEvent;
using calstand::wire::test::decode;

TEST(SseEncoder, WritesIdTypeAndDataThenABlankLine) {
  EXPECT_EQ(encode_sse_event({"step", "{\"step\":1}", "17-3"}),
            "id: 17-3\nevent: step\ndata: {\"step\":1}\n\n");
  EXPECT_EQ(encode_sse_event({"station", "{}", ""}), "event: station\ndata: {}\n\n");
  EXPECT_EQ(encode_sse_event({"", "x", ""}), "data: x\n\n");
}

TEST(SseEncoder, DataWithLineBreaksBecomesSeveralDataLines) {
  EXPECT_EQ(encode_sse_event({"m", "a\nb\r\nc\rd", ""}),
            "event: m\ndata: a\ndata: b\ndata: c\ndata: d\n\n");
  EXPECT_EQ(encode_sse_event({"m", "a\n", ""}), "event: m\ndata: a\ndata: \n\n");
  EXPECT_EQ(encode_sse_event({"m", "", ""}), "event: m\ndata: \n\n");
}

TEST(SseEncoder, EventsComeBackAsTheyWereWritten) {
  const std::vector<SseEvent> sent = {{"station", "{\"name\": \"s\"}", ""},
                                      {"step", "line one\nline two", "9-1"},
                                      {"run", "", "9-2"},
                                      {"gap", "  leading spaces\n\ntrailing\n", "9-3"},
                                      {"message", ": not a comment", "9-4"}};
  std::string stream = encode_sse_retry(1500) + encode_sse_comment("hello");
  for (const auto& e : sent) stream += encode_sse_event(e) + encode_sse_comment("keep-alive");
  const auto got = decode(stream);
  ASSERT_EQ(got.size(), sent.size());
  for (std::size_t i = 0; i < sent.size(); ++i) {
    EXPECT_EQ(got[i].type, sent[i].type) << i;
    EXPECT_EQ(got[i].data, sent[i].data) << i;
    EXPECT_EQ(got[i].id, sent[i].id) << i;
  }
}

TEST(SseEncoder, CrLfInDataComesBackAsLf) {
  const auto got = decode(encode_sse_event({"m", "a\r\nb\rc", ""}));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].data, "a\nb\nc");
}

TEST(SseEncoder, RefusesAnIdOrTypeThatNoFieldCanCarry) {
  EXPECT_THROW(encode_sse_event({"step", "x", "1\n2"}), std::invalid_argument);
  EXPECT_THROW(encode_sse_event({"st\rep", "x", "1"}), std::invalid_argument);
  EXPECT_THROW(encode_sse_event({"step", "x", std::string("1\0", 2)}), std::invalid_argument);
}

TEST(SseEncoder, CommentsAndRetryDispatchNothing) {
  EXPECT_EQ(encode_sse_comment("keep-alive"), ": keep-alive\n\n");
  EXPECT_EQ(encode_sse_comment("two\nlines"), ": two lines\n\n");
  SseDecoder d([](const SseEvent&) {
    ADD_FAILURE() << "no event expected";
    return true;
  });
  ASSERT_TRUE(d.feed(encode_sse_comment("a\nb") + encode_sse_retry(2000)));
  EXPECT_EQ(d.retry_ms(), 2000u);
}

}  // namespace

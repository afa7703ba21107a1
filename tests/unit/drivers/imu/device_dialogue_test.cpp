#include "drivers/device_dialogue.hpp"

#include <gtest/gtest.h>

#include <deque>

#include "drivers/imu_wire_format.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

/// A device on a test link: streams `noise` before every answer, and answers a request with
/// "OK<request>" only from the `answer_from`-th request on (a device busy after a reset).
class ScriptedLink final : public ByteTransport {
 public:
  explicit ScriptedLink(int answer_from) : answer_from_(answer_from) {}
  IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds) override {
    if (pending_.empty()) return {};
    std::size_t n = 0;
    // Two bytes a read: the reply must be found across reads.
    while (n < buffer.size() && n < 2 && !pending_.empty()) {
      buffer[n++] = pending_.front();
      pending_.pop_front();
    }
    return {n, {}};
  }
  IoResult write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds) override {
    ++requests;
    for (std::uint8_t b : std::string("xx\x01")) pending_.push_back(b);
    if (requests >= answer_from_) {
      pending_.push_back('O');
      pending_.push_back('K');
      pending_.insert(pending_.end(), bytes.begin(), bytes.end());
      pending_.push_back(';');
    }
    return {bytes.size(), {}};
  }
  int requests = 0;

 private:
  int answer_from_;
  std::deque<std::uint8_t> pending_;
};

/// The reply "OK...;" anywhere in what arrived.
std::optional<std::vector<std::uint8_t>> find_ok(std::span<const std::uint8_t> received) {
  const std::string text(received.begin(), received.end());
  const auto begin = text.find("OK");
  if (begin == std::string::npos) return std::nullopt;
  const auto end = text.find(';', begin);
  if (end == std::string::npos) return std::nullopt;
  return std::vector<std::uint8_t>(received.begin() + static_cast<std::ptrdiff_t>(begin),
                                   received.begin() + static_cast<std::ptrdiff_t>(end + 1));
}

TEST(DeviceDialogue, FindsTheReplyAmongStreamedBytesAcrossReads) {
  ScriptedLink link(1);
  const std::vector<std::uint8_t> request{'I', 'D', '?'};
  const auto reply = request_reply(link, request, find_ok, 50ms, 3, "ID?");
  EXPECT_EQ(std::string(reply.begin(), reply.end()), "OKID?;");
  EXPECT_EQ(link.requests, 1);
}

TEST(DeviceDialogue, RetriesARequestThatGotNoReply) {
  ScriptedLink link(3);
  const std::vector<std::uint8_t> request{'I', 'D', '?'};
  const auto reply = request_reply(link, request, find_ok, 20ms, 3, "ID?");
  EXPECT_EQ(std::string(reply.begin(), reply.end()), "OKID?;");
  EXPECT_EQ(link.requests, 3);
}

TEST(DeviceDialogue, NamesTheRequestThatNeverGotAReply) {
  ScriptedLink link(99);
  const std::vector<std::uint8_t> request{'I', 'D', '?'};
  try {
    request_reply(link, request, find_ok, 10ms, 2, "ReqDID");
    FAIL() << "no reply must throw";
  } catch (const DeviceConfigError& e) {
    EXPECT_STREQ(e.what(), "no reply to ReqDID within 10 ms (2 attempts)");
  }
  EXPECT_EQ(link.requests, 2);
}

TEST(ImuWireFormat, KnowsEveryFormatByNameAndRefusesOthersNamingThem) {
  for (const auto& name : imu_wire_format_names()) {
    EXPECT_EQ(imu_wire_format(name, "format").name(), name);
  }
  try {
    imu_wire_format("nmea", "imus[0].connection.format");
    FAIL() << "an unknown format must be refused";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("imus[0].connection.format"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("xsens"), std::string::npos);
  }
}

}  // namespace
}  // namespace calstand::drivers

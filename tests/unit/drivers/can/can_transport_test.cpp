#include "drivers/can_transport.hpp"

#include <gtest/gtest.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <stdexcept>
#include <string>

#include "drivers/socketcan_port.hpp"
#include "drivers/socketpair_can.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;
using Status = CanReadResult::Status;

can_frame frame(canid_t id, std::uint8_t first_byte = 0) {
  can_frame f{};
  f.can_id = id;
  f.len = 8;
  f.data[0] = first_byte;
  return f;
}

TEST(CanFiltersTest, ExactIdsTellStandardFromExtendedAndRefuseRemoteFrames) {
  const canid_t ids[] = {0x101, 0x101 | CAN_EFF_FLAG, 0x18FF0001 | CAN_EFF_FLAG};
  const auto filters = exact_id_filters(ids);
  EXPECT_TRUE(passes_filters(0x101, filters));
  EXPECT_TRUE(passes_filters(0x101 | CAN_EFF_FLAG, filters));
  EXPECT_TRUE(passes_filters(0x18FF0001 | CAN_EFF_FLAG, filters));
  EXPECT_FALSE(passes_filters(0x102, filters));
  EXPECT_FALSE(passes_filters(0x101 | CAN_RTR_FLAG, filters));
  EXPECT_FALSE(passes_filters(0x18FF0001, filters));  // same number, standard frame
  EXPECT_TRUE(passes_filters(0x7FF | CAN_RTR_FLAG, exact_id_filters({})));  // empty: everything
}

TEST(SocketPairCanTest, FramesCrossThePairIntact) {
  auto [a, b] = SocketPairCan::make_pair();
  const can_frame sent = frame(0x123 | CAN_EFF_FLAG, 0xAB);
  ASSERT_EQ(a->write(sent, 100ms), "");
  const CanReadResult r = b->read(1000ms);
  ASSERT_EQ(r.status, Status::kFrame) << r.message;
  EXPECT_EQ(r.frame.frame.can_id, sent.can_id);
  EXPECT_EQ(r.frame.frame.len, 8);
  EXPECT_EQ(std::memcmp(r.frame.frame.data, sent.data, 8), 0);
  // Linux stamps Unix socket messages too; when it does the stamp is the wall clock now.
  if (r.frame.kernel_time_s) {
    const double now_s =
        std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
    EXPECT_NEAR(*r.frame.kernel_time_s, now_s, 1.0);
  }
}

TEST(SocketPairCanTest, ATimeoutReadsAsNothingWithinTheTime) {
  auto [a, b] = SocketPairCan::make_pair();
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(b->read(30ms).status, Status::kTimeout);
  const auto waited = std::chrono::steady_clock::now() - start;
  EXPECT_GE(waited, 25ms);
  EXPECT_LT(waited, 500ms);
}

TEST(SocketPairCanTest, FiltersRunInUserSpace) {
  auto [a, b] = SocketPairCan::make_pair();
  const canid_t ids[] = {0x101, 0x103};
  b->set_filters(ids);
  for (canid_t id : {0x100u, 0x101u, 0x102u, 0x103u | CAN_RTR_FLAG, 0x103u}) {
    ASSERT_EQ(a->write(frame(id), 100ms), "");
  }
  EXPECT_EQ(b->read(500ms).frame.frame.can_id, 0x101u);
  EXPECT_EQ(b->read(500ms).frame.frame.can_id, 0x103u);
  EXPECT_EQ(b->read(20ms).status, Status::kTimeout);
}

TEST(SocketPairCanTest, AWrongSizedMessageIsMalformedAndTheLinkLives) {
  auto [a, b] = SocketPairCan::make_pair();
  const char junk[5] = {1, 2, 3, 4, 5};
  ASSERT_EQ(::send(a->fd(), junk, sizeof junk, 0), 5);
  char big[40] = {};
  ASSERT_EQ(::send(a->fd(), big, sizeof big, 0), 40);
  const CanReadResult r1 = b->read(500ms);
  EXPECT_EQ(r1.status, Status::kMalformed);
  EXPECT_NE(r1.message.find("5 bytes is not a can_frame"), std::string::npos) << r1.message;
  EXPECT_EQ(b->read(500ms).status, Status::kMalformed);
  ASSERT_EQ(a->write(frame(0x101), 100ms), "");
  EXPECT_EQ(b->read(500ms).status, Status::kFrame);
}

TEST(SocketPairCanTest, APeerClosingIsALinkErrorAndCannotBeReopened) {
  auto [a, b] = SocketPairCan::make_pair();
  a.reset();
  const CanReadResult r = b->read(500ms);
  EXPECT_EQ(r.status, Status::kError);
  EXPECT_NE(r.message.find("end of stream"), std::string::npos) << r.message;
  EXPECT_NE(b->write(frame(0x101), 50ms), "");
  b->close();
  EXPECT_THROW(b->open(), std::runtime_error);
}

TEST(SocketCanPortTest, AMissingInterfaceIsNamedWithAHint) {
  SocketCanPort port("calcan9");  // constructing does no I/O
  try {
    port.open();
    FAIL() << "opened a missing interface";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("calcan9: no such interface", 0), 0u) << what;
    EXPECT_NE(what.find("ip link"), std::string::npos) << what;
  }
}

TEST(SocketCanPortTest, ANonCanInterfaceIsRefusedByName) {
  // "lo" exists everywhere; it is not CAN (or the kernel has no CAN at all): either way an
  // error naming it.
  SocketCanPort port("lo");
  try {
    port.open();
    FAIL() << "opened lo as a CAN interface";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("lo: ", 0), 0u) << e.what();
  }
  EXPECT_THROW(SocketCanPort("an-interface-name-too-long").open(), std::runtime_error);
}

TEST(SocketCanPortTest, Vcan0CarriesFramesWithKernelTimes) {
  if (::if_nametoindex("vcan0") == 0) {
    GTEST_SKIP() << "no vcan0 on this machine: modprobe vcan; ip link add dev vcan0 type vcan; "
                    "ip link set up vcan0";
  }
  SocketCanPort sender("vcan0");
  SocketCanPort receiver("vcan0");
  const canid_t ids[] = {0x101};
  receiver.set_filters(ids);
  try {
    sender.open();
    receiver.open();
  } catch (const std::runtime_error& e) {
    GTEST_SKIP() << "vcan0 exists but cannot be opened here: " << e.what();
  }
  ASSERT_EQ(sender.write(frame(0x100), 100ms), "");
  ASSERT_EQ(sender.write(frame(0x101, 7), 100ms), "");
  const CanReadResult r = receiver.read(1000ms);
  ASSERT_EQ(r.status, Status::kFrame) << r.message;
  EXPECT_EQ(r.frame.frame.can_id, 0x101u);  // 0x100 stayed in the kernel's filter
  EXPECT_EQ(r.frame.frame.data[0], 7);
  EXPECT_TRUE(r.frame.kernel_time_s.has_value());
}

}  // namespace
}  // namespace calstand::drivers

// ModbusChamber when the controller's answers are garbage: a TCP proxy between the driver and
// our server mangles the responses in several ways. The driver must count, fault and recover,
// never crash or believe a value.

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <thread>

#include "drivers/modbus_chamber.hpp"
#include "drivers/modbus_chamber_server.hpp"
#include "modbus_test_support.hpp"

namespace calstand::drivers {
namespace {

using namespace test;

enum class Mangle { kNone, kTruncate, kNoise, kWrongTransaction, kTrailingJunk, kCount };

/// Forwards one TCP client at a time to 127.0.0.1:`upstream_port`, mangling responses.
class ManglingProxy {
 public:
  explicit ManglingProxy(int upstream_port) : upstream_port_(upstream_port) {
    listen_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr = loopback(0);
    ::bind(listen_, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    ::listen(listen_, 4);
    socklen_t len = sizeof addr;
    ::getsockname(listen_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
    thread_ = std::thread([this] { run(); });
  }
  ~ManglingProxy() {
    stop_ = true;
    thread_.join();
    ::close(listen_);
  }
  int port() const { return port_; }
  std::atomic<Mangle> mangle{Mangle::kNone};

 private:
  static sockaddr_in loopback(int port) {
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    return addr;
  }

  void run() {
    while (!stop_) {
      pollfd p{listen_, POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      const int client = ::accept(listen_, nullptr, nullptr);
      const int upstream = ::socket(AF_INET, SOCK_STREAM, 0);
      sockaddr_in addr = loopback(upstream_port_);
      if (client >= 0 &&
          ::connect(upstream, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
        relay(client, upstream);
      }
      if (client >= 0) ::close(client);
      ::close(upstream);
    }
  }

  void relay(int client, int upstream) {
    std::uint8_t buf[512];
    while (!stop_) {
      pollfd fds[2] = {{client, POLLIN, 0}, {upstream, POLLIN, 0}};
      if (::poll(fds, 2, 50) <= 0) continue;
      if (fds[0].revents) {
        const auto n = ::read(client, buf, sizeof buf);
        if (n <= 0 || ::send(upstream, buf, std::size_t(n), MSG_NOSIGNAL) != n) return;
      }
      if (fds[1].revents) {
        auto n = ::read(upstream, buf, sizeof buf);
        if (n <= 0) return;
        switch (mangle.load()) {
          case Mangle::kTruncate:
            n = n / 2;
            break;
          case Mangle::kNoise:
            for (ssize_t i = 0; i < n; ++i) buf[i] = static_cast<std::uint8_t>(buf[i] * 31 + 7);
            break;
          case Mangle::kWrongTransaction:
            buf[0] ^= 0x55;
            break;
          case Mangle::kTrailingJunk:
            buf[n++] = 0xAB;
            buf[n++] = 0xCD;
            break;
          case Mangle::kNone:
          case Mangle::kCount:
            break;
        }
        // MSG_NOSIGNAL: a client that hung up must end this relay, not the test (SIGPIPE).
        if (::send(client, buf, std::size_t(n), MSG_NOSIGNAL) != n) return;
      }
    }
  }

  int upstream_port_;
  int listen_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST(ModbusChamberGarbage, MangledResponsesAreCountedFaultedAndSurvived) {
  const auto station = quick_chamber_station();
  RunningWorld w(station, 1.0);
  SimChamberBackend backend(w.world, w.mutex);
  auto server = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
  server->start();
  ManglingProxy proxy(server->port());

  auto config = station.chamber;
  config.backend = "modbus";
  config.connection = {{"transport", "tcp"},  {"host", "127.0.0.1"}, {"port", proxy.port()},
                       {"map", "watlow-f4t"}, {"timeout_ms", 50},    {"poll_period_ms", 10},
                       {"stale_after_s", 0.3}};
  ModbusChamber chamber(ModbusChamberOptions::from_config(config), w.clock);
  ASSERT_TRUE(chamber.configure());
  ASSERT_TRUE(chamber.activate());
  const double good_c = chamber.read_state().air_temperature_c;

  for (int m = 1; m < int(Mangle::kCount); ++m) {
    proxy.mangle = static_cast<Mangle>(m);
    EXPECT_TRUE(eventually([&] { return chamber.read_state().fault; }, 2000ms))
        << "mangle mode " << m;
    const auto s = chamber.read_state();
    // Whatever came back, the reading is the last good one or a fault, never noise.
    EXPECT_NEAR(s.air_temperature_c, good_c, 1.0) << "mangle mode " << m;
    proxy.mangle = Mangle::kNone;
    EXPECT_TRUE(eventually([&] { return !chamber.read_state().fault; }, 4000ms))
        << "recovers after mangle mode " << m << ": " << chamber.read_state().fault_text;
  }
  const auto counters = chamber.fault_counters();
  EXPECT_GE(counters.at("bad_responses") + counters.at("timeouts"), 4u);
  EXPECT_GE(counters.at("reconnects"), 1u);
  EXPECT_EQ(chamber.state(), DeviceState::kActive);
}

}  // namespace
}  // namespace calstand::drivers

#include "drivers/tcp_client.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/error.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;
using SteadyClock = std::chrono::steady_clock;

/// A listening socket on 127.0.0.1 that the test closes and reopens on the same port.
class Listener {
 public:
  explicit Listener(std::uint16_t port = 0) { open(port); }
  ~Listener() {
    close_peer();
    close();
  }
  void open(std::uint16_t port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    const int one = 1;
    ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in sa{};
    sa.sin_family = AF_INET;
    sa.sin_port = htons(port);
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0 || ::listen(fd_, 4) != 0) {
      throw std::runtime_error("test listener: cannot bind");
    }
    socklen_t len = sizeof sa;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&sa), &len);
    port_ = ntohs(sa.sin_port);
  }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  /// Accepts one connection (waiting up to 2 s); true if one came.
  bool accept() {
    pollfd pfd{fd_, POLLIN, 0};
    if (::poll(&pfd, 1, 2000) != 1) return false;
    peer_ = ::accept(fd_, nullptr, nullptr);
    return peer_ >= 0;
  }
  void send(const std::string& s) const {
    ASSERT_EQ(::send(peer_, s.data(), s.size(), 0), static_cast<ssize_t>(s.size()));
  }
  std::string receive(std::size_t count) const {
    std::string out;
    while (out.size() < count) {
      pollfd pfd{peer_, POLLIN, 0};
      if (::poll(&pfd, 1, 2000) != 1) break;
      char buf[256];
      const ssize_t n = ::recv(peer_, buf, sizeof buf, 0);
      if (n <= 0) break;
      out.append(buf, static_cast<std::size_t>(n));
    }
    return out;
  }
  void close_peer() {
    if (peer_ >= 0) ::close(peer_);
    peer_ = -1;
  }
  std::uint16_t port() const { return port_; }

 private:
  int fd_ = -1;
  int peer_ = -1;
  std::uint16_t port_ = 0;
};

TcpOptions options_for(std::uint16_t port) {
  TcpOptions o;
  o.port = port;
  o.connect_timeout = 500ms;
  o.initial_backoff = 40ms;
  o.max_backoff = 160ms;
  return o;
}

IoResult write_text(TcpClient& c, const std::string& s, std::chrono::milliseconds timeout = 500ms) {
  return c.write(
      std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()),
      timeout);
}

std::string read_text(TcpClient& c, std::chrono::milliseconds timeout, IoResult* result = nullptr) {
  std::uint8_t buf[256];
  const IoResult r = c.read(buf, timeout);
  if (result != nullptr) *result = r;
  return {reinterpret_cast<const char*>(buf), r.bytes};
}

TEST(ReconnectBackoff, DoublesUpToTheBoundAndResetsOnSuccess) {
  ReconnectBackoff b(100ms, 500ms);
  const SteadyClock::time_point t0{};
  EXPECT_TRUE(b.may_attempt(t0));
  b.failed(t0);  // next not before t0 + 100 ms
  EXPECT_FALSE(b.may_attempt(t0 + 99ms));
  EXPECT_EQ(b.wait_left(t0 + 40ms), 60ms);
  EXPECT_TRUE(b.may_attempt(t0 + 100ms));
  std::chrono::milliseconds delays[5];
  for (auto& d : delays) {
    d = b.next_delay();
    b.failed(t0);
  }
  EXPECT_EQ(delays[0], 200ms);
  EXPECT_EQ(delays[1], 400ms);
  EXPECT_EQ(delays[2], 500ms);  // bounded
  EXPECT_EQ(delays[4], 500ms);
  b.succeeded();
  EXPECT_EQ(b.next_delay(), 100ms);
  b.lost(t0 + 1s);  // a link that worked is retried at once
  EXPECT_TRUE(b.may_attempt(t0 + 1s));
}

TEST(TcpClient, OptionsNameTheBrokenField) {
  TcpOptions o;
  o.port = 0;
  try {
    o.validate();
    FAIL() << "port 0 accepted";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "tcp.port");
  }
  o.port = 1;
  o.host.clear();
  EXPECT_THROW(o.validate(), core::InputError);
}

TEST(TcpClient, ExchangesBytesAndTimesOutWithNothing) {
  Listener server;
  TcpClient client(options_for(server.port()));
  EXPECT_FALSE(client.is_connected());  // the constructor does no I/O
  ASSERT_TRUE(write_text(client, "*idn?\n").ok());
  ASSERT_TRUE(server.accept());
  EXPECT_EQ(server.receive(6), "*idn?\n");
  server.send("CALSTAND\n");
  EXPECT_EQ(read_text(client, 1s), "CALSTAND\n");

  const auto t0 = SteadyClock::now();
  IoResult r;
  EXPECT_EQ(read_text(client, 100ms, &r), "");
  const auto waited = SteadyClock::now() - t0;
  EXPECT_TRUE(r.ok()) << r.error;  // a timeout is not an error
  EXPECT_GE(waited, 90ms);
  EXPECT_LT(waited, 400ms);
  EXPECT_EQ(client.reconnects(), 0u);
}

TEST(TcpClient, RefusedConnectionsBackOffAndNeverBlockTheCaller) {
  std::uint16_t port = 0;
  {
    Listener probe;  // a port that was free a moment ago and now has nobody listening
    port = probe.port();
  }
  TcpClient client(options_for(port));
  IoResult r;
  read_text(client, 200ms, &r);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error.find("127.0.0.1:" + std::to_string(port)), std::string::npos) << r.error;
  EXPECT_EQ(client.failed_attempts(), 1u);

  // Within the backoff the call fails at once, without an attempt, saying when the next is due.
  const auto t0 = SteadyClock::now();
  read_text(client, 500ms, &r);
  EXPECT_LT(SteadyClock::now() - t0, 30ms);
  EXPECT_NE(r.error.find("next attempt in"), std::string::npos) << r.error;
  EXPECT_EQ(client.failed_attempts(), 1u);

  // Attempts keep failing at growing intervals: 40, 80, 160, 160 ms.
  const auto start = SteadyClock::now();
  while (client.failed_attempts() < 5 && SteadyClock::now() - start < 2s) {
    read_text(client, 20ms, &r);
  }
  const auto spent = SteadyClock::now() - start;
  EXPECT_EQ(client.failed_attempts(), 5u);
  EXPECT_GE(spent, 400ms);  // 40 + 80 + 160 + 160 - scheduling slack
  EXPECT_LT(spent, 1500ms);
}

TEST(TcpClient, ConnectAttemptIsBoundedByTheCallersTimeout) {
  // A listener that never accepts, its queue filled: further SYNs are dropped, so a connect
  // would wait for the kernel's SYN retries (seconds) if the client did not bound it.
  Listener server;
  std::vector<std::unique_ptr<TcpClient>> fillers;
  for (int i = 0; i < 8; ++i) {
    fillers.push_back(std::make_unique<TcpClient>(options_for(server.port())));
    fillers.back()->connect(50ms);
  }
  TcpOptions o = options_for(server.port());
  o.connect_timeout = 5000ms;
  TcpClient client(o);
  const auto t0 = SteadyClock::now();
  IoResult r;
  read_text(client, 100ms, &r);
  const auto took = SteadyClock::now() - t0;
  EXPECT_LT(took, 400ms);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error.find("connect timed out after 100 ms"), std::string::npos) << r.error;
}

TEST(TcpClient, ReconnectsAfterTheServerGoesAwayAndComesBack) {
  Listener server;
  const std::uint16_t port = server.port();
  TcpClient client(options_for(port));
  ASSERT_TRUE(client.connect(500ms).empty());
  ASSERT_TRUE(server.accept());

  // The server closes the connection and stops listening.
  server.close_peer();
  server.close();
  IoResult r;
  read_text(client, 500ms, &r);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error.find("end of stream"), std::string::npos) << r.error;
  EXPECT_FALSE(client.is_connected());
  // Writing to it while it is gone is an error, not a SIGPIPE.
  EXPECT_FALSE(write_text(client, ":stop 1\n").ok());

  server.open(port);
  bool back = false;
  for (int i = 0; i < 50 && !back; ++i) {
    back = write_text(client, ":stop 1\n", 50ms).ok();
    if (!back) std::this_thread::sleep_for(20ms);
  }
  ASSERT_TRUE(back);
  ASSERT_TRUE(server.accept());
  EXPECT_EQ(server.receive(8), ":stop 1\n");
  EXPECT_EQ(client.reconnects(), 1u);
  EXPECT_GE(client.failed_attempts(), 1u);
}

}  // namespace
}  // namespace calstand::drivers

#include "drivers/acutrol_server.hpp"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <stdexcept>

#include "drivers/fd_io.hpp"
#include "drivers/pseudo_terminal.hpp"
#include "drivers/tcp_client.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

/// How often blocked threads look at the stop flag: stop() returns within about this [ms].
constexpr auto kPollSlice = 50ms;
constexpr auto kReplyTimeout = 1000ms;  // a client that does not read its replies is dropped

/// ByteTransport over an accepted socket (the server's end of one client connection).
class SocketLink final : public ByteTransport {
 public:
  SocketLink(int fd, std::string who) : fd_(fd), who_(std::move(who)) {}
  ~SocketLink() override { ::close(fd_); }
  SocketLink(const SocketLink&) = delete;
  SocketLink& operator=(const SocketLink&) = delete;
  IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override {
    return read_fd(fd_, buffer, timeout, who_);
  }
  IoResult write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout) override {
    return send_fd(fd_, bytes, timeout, who_);
  }
  /// Unblocks the session's reads (drop_clients / stop) without closing the descriptor, which
  /// the session thread still owns.
  void shut() { ::shutdown(fd_, SHUT_RDWR); }

 private:
  int fd_;
  std::string who_;
};

}  // namespace

struct AcutrolServer::Session {
  std::unique_ptr<SocketLink> link;
  std::atomic<bool> dropped{false};
  std::atomic<bool> done{false};
  std::thread thread;
};

AcutrolServer::AcutrolServer(TableServerBackend& backend, AcutrolServerOptions options)
    : handler_([&backend](std::string_view line, bool overlong) -> std::optional<std::string> {
        if (overlong) {
          return acutrol::format_error(
              acutrol::ErrorCode::kLineTooLong,
              fmt::format("line longer than {} bytes", acutrol::kMaxLineBytes));
        }
        return handle_command_line(line, backend);
      }),
      options_(std::move(options)) {}

AcutrolServer::AcutrolServer(LineHandler handler, AcutrolServerOptions options)
    : handler_(std::move(handler)), options_(std::move(options)) {}

AcutrolServer::~AcutrolServer() { stop(); }

void AcutrolServer::start() {
  if (listen_fd_ >= 0) return;
  const std::string where = fmt::format("acutrol server {}:{}", options_.bind_host, options_.port);
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(options_.port);
  if (::inet_pton(AF_INET, options_.bind_host.c_str(), &sa.sin_addr) != 1) {
    throw std::runtime_error(where + ": bind_host is not an IPv4 address");
  }
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error(os_error_text(where, "socket", errno));
  // A restarted simulator must get its port back while old connections sit in TIME_WAIT.
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&sa), sizeof sa) != 0 || ::listen(fd, 8) != 0) {
    const int err = errno;
    ::close(fd);
    throw std::runtime_error(os_error_text(where, "bind/listen", err));
  }
  socklen_t len = sizeof sa;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&sa), &len);
  port_ = ntohs(sa.sin_port);
  listen_fd_ = fd;
  stopping_ = false;
  accept_thread_ = std::thread([this] { accept_loop(); });
}

std::string AcutrolServer::start_serial() {
  if (!pty_) {
    pty_ = std::make_unique<PseudoTerminal>();
    stopping_ = false;
    pty_thread_ = std::thread([this] {
      const std::atomic<bool> never_dropped{false};
      serve(*pty_, never_dropped);
    });
  }
  return pty_->slave_path();
}

void AcutrolServer::stop() noexcept {
  stopping_ = true;
  if (accept_thread_.joinable()) accept_thread_.join();
  reap_sessions(true);
  if (pty_thread_.joinable()) pty_thread_.join();
  pty_.reset();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
}

void AcutrolServer::drop_clients() {
  std::lock_guard lock(sessions_mutex_);
  for (auto& s : sessions_) {
    s->dropped = true;
    s->link->shut();
  }
}

void AcutrolServer::reap_sessions(bool all) {
  std::lock_guard lock(sessions_mutex_);
  for (auto it = sessions_.begin(); it != sessions_.end();) {
    if (all || (*it)->done) {
      if (all) (*it)->link->shut();
      if ((*it)->thread.joinable()) (*it)->thread.join();
      it = sessions_.erase(it);
    } else {
      ++it;
    }
  }
}

void AcutrolServer::accept_loop() {
  while (!stopping_) {
    reap_sessions(false);
    pollfd pfd{listen_fd_, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, static_cast<int>(kPollSlice.count()));
    if (ready <= 0) continue;
    sockaddr_in peer{};
    socklen_t len = sizeof peer;
    const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &len,
                             SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) continue;
    if (refusing_ || clients_ >= options_.max_clients) {
      ::close(fd);  // refused by closing: the client sees end of stream
      continue;
    }
    char address[INET_ADDRSTRLEN] = "?";
    ::inet_ntop(AF_INET, &peer.sin_addr, address, sizeof address);
    auto session = std::make_unique<Session>();
    session->link = std::make_unique<SocketLink>(
        fd, fmt::format("acutrol client {}:{}", address, ntohs(peer.sin_port)));
    Session* s = session.get();
    ++clients_;
    // Listed before it runs, so that drop_clients() never misses a session that has answered.
    std::lock_guard lock(sessions_mutex_);
    sessions_.push_back(std::move(session));
    s->thread = std::thread([this, s] {
      serve(*s->link, s->dropped);
      --clients_;
      s->done = true;
    });
  }
}

void AcutrolServer::serve(ByteTransport& link, const std::atomic<bool>& dropped) {
  acutrol::LineAssembler lines;
  std::uint8_t buffer[512];
  while (!stopping_ && !dropped) {
    const IoResult r = link.read(buffer, kPollSlice);
    if (!r.ok()) return;  // the client hung up or the link failed: end of session
    if (options_.cr_ends_line)
      std::replace(buffer, buffer + r.bytes, std::uint8_t{'\r'}, std::uint8_t{'\n'});
    lines.push(std::span<const std::uint8_t>(buffer, r.bytes));
    while (auto line = lines.next()) {
      std::optional<std::string> answer = handler_(line->text, line->overlong);
      ++commands_;
      if (!answering_ || !answer) continue;
      std::string reply = std::move(*answer);
      reply += options_.reply_terminator;
      const auto* bytes = reinterpret_cast<const std::uint8_t*>(reply.data());
      if (!link.write(std::span<const std::uint8_t>(bytes, reply.size()), kReplyTimeout).ok()) {
        return;
      }
    }
  }
}

}  // namespace calstand::drivers

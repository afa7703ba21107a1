#pragma once
// A datagram socket standing in for systemd in the tests: the receiving end of sd_notify(3)'s
// protocol ($NOTIFY_SOCKET: "KEY=VALUE" lines, one message a datagram) and of the journal's
// native protocol (systemd.io "Native Journal Protocol"), read here independently of the
// daemon's code that writes them.

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace calstand::testing {

/// One message: its assignments by key (a key given twice: the last).
using NotifyMessage = std::map<std::string, std::string>;

/// "READY=1\nSTATUS=idle\n" -> {READY: 1, STATUS: idle}.
inline NotifyMessage parse_notify_message(const std::string& datagram) {
  NotifyMessage out;
  std::size_t pos = 0;
  while (pos < datagram.size()) {
    std::size_t end = datagram.find('\n', pos);
    if (end == std::string::npos) end = datagram.size();
    const std::string line = datagram.substr(pos, end - pos);
    const auto eq = line.find('=');
    if (eq != std::string::npos) out[line.substr(0, eq)] = line.substr(eq + 1);
    pos = end + 1;
  }
  return out;
}

/// A journal datagram's fields: "KEY=VALUE\n", or "KEY\n" + 64-bit little-endian length +
/// value + "\n". Throws std::runtime_error on a malformed one.
inline NotifyMessage parse_journal_datagram(const std::string& d) {
  NotifyMessage out;
  std::size_t pos = 0;
  while (pos < d.size()) {
    const std::size_t nl = d.find('\n', pos);
    const std::size_t eq = d.find('=', pos);
    if (nl == std::string::npos) throw std::runtime_error("journal field without a newline");
    if (eq != std::string::npos && eq < nl) {
      out[d.substr(pos, eq - pos)] = d.substr(eq + 1, nl - eq - 1);
      pos = nl + 1;
      continue;
    }
    const std::string key = d.substr(pos, nl - pos);
    if (nl + 9 > d.size()) throw std::runtime_error("journal field " + key + ": no length");
    std::uint64_t size = 0;
    for (int i = 0; i < 8; ++i) {
      size |= static_cast<std::uint64_t>(static_cast<unsigned char>(d[nl + 1 + i])) << (8 * i);
    }
    const std::size_t start = nl + 9;
    if (start + size + 1 > d.size() || d[start + size] != '\n') {
      throw std::runtime_error("journal field " + key + ": bad length");
    }
    out[key] = d.substr(start, size);
    pos = start + size + 1;
  }
  return out;
}

class DatagramPeer {
 public:
  /// Binds a datagram socket at `address`: a path, or '@' and an abstract name.
  explicit DatagramPeer(std::string address) : address_(std::move(address)) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw std::runtime_error("socket");
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::memcpy(addr.sun_path, address_.data(), address_.size());
    socklen_t len = sizeof(addr);
    if (address_[0] == '@') {
      addr.sun_path[0] = '\0';
      len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + address_.size());
    } else {
      ::unlink(address_.c_str());
    }
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), len) != 0) {
      throw std::runtime_error("bind " + address_);
    }
  }
  ~DatagramPeer() {
    ::close(fd_);
    if (address_[0] != '@') ::unlink(address_.c_str());
  }
  DatagramPeer(const DatagramPeer&) = delete;
  DatagramPeer& operator=(const DatagramPeer&) = delete;
  const std::string& address() const { return address_; }

  /// The next datagram within `timeout`, or none.
  std::optional<std::string> next(std::chrono::milliseconds timeout) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(timeout.count())) <= 0) return std::nullopt;
    std::string buf(1 << 16, '\0');
    const ssize_t n = ::recv(fd_, buf.data(), buf.size(), 0);
    if (n < 0) return std::nullopt;
    buf.resize(static_cast<std::size_t>(n));
    return buf;
  }
  /// Every datagram that arrives within `window`, with its arrival time.
  std::vector<std::pair<std::chrono::steady_clock::time_point, std::string>> collect(
      std::chrono::milliseconds window) {
    std::vector<std::pair<std::chrono::steady_clock::time_point, std::string>> out;
    const auto end = std::chrono::steady_clock::now() + window;
    while (true) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          end - std::chrono::steady_clock::now());
      if (left.count() <= 0) break;
      if (auto d = next(left)) out.emplace_back(std::chrono::steady_clock::now(), std::move(*d));
    }
    return out;
  }
  /// Reads notify messages until one satisfies `done` (returned) or `timeout` passes.
  template <class Pred>
  std::optional<NotifyMessage> wait_for(Pred done, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (true) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          end - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      const auto d = next(left);
      if (!d) return std::nullopt;
      NotifyMessage m = parse_notify_message(*d);
      if (done(m)) return m;
    }
  }

 private:
  std::string address_;
  int fd_ = -1;
};

}  // namespace calstand::testing

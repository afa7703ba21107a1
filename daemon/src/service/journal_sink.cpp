#include "daemon/service/journal_sink.hpp"

#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <system_error>

#include "daemon/service/log_fields.hpp"

namespace calstand::daemon::service {
namespace {

void append_field(std::string& out, std::string_view key, std::string_view value) {
  out.append(key);
  if (value.find('\n') == std::string_view::npos) {
    out.append("=").append(value).append("\n");
    return;
  }
  out.append("\n");
  std::uint64_t size = value.size();
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((size >> (8 * i)) & 0xff));
  out.append(value).append("\n");
}

// syslog(3) priorities of spdlog's levels.
int syslog_priority(spdlog::level::level_enum level) {
  switch (level) {
    case spdlog::level::critical:
      return 2;
    case spdlog::level::err:
      return 3;
    case spdlog::level::warn:
      return 4;
    case spdlog::level::info:
      return 6;
    default:
      return 7;
  }
}

}  // namespace

bool stderr_is_journal() {
  const char* stream = std::getenv("JOURNAL_STREAM");
  if (stream == nullptr) return false;
  unsigned long long device = 0;
  unsigned long long inode = 0;
  if (std::sscanf(stream, "%llu:%llu", &device, &inode) != 2) return false;
  struct stat st {};
  if (::fstat(STDERR_FILENO, &st) != 0) return false;
  return st.st_dev == device && st.st_ino == inode;
}

std::string journal_message(const std::string& identifier, int priority,
                            const std::string& message) {
  std::string out;
  append_field(out, "MESSAGE", message);
  append_field(out, "PRIORITY", std::to_string(priority));
  append_field(out, "SYSLOG_IDENTIFIER", identifier);
  const LogFields& fields = thread_log_fields();
  if (fields.run) append_field(out, "RUN", std::to_string(*fields.run));
  if (fields.step) append_field(out, "STEP", std::to_string(*fields.step));
  if (fields.device) append_field(out, "DEVICE", *fields.device);
  return out;
}

JournalSink::JournalSink(std::string identifier, std::string socket_path)
    : identifier_(std::move(identifier)), socket_path_(std::move(socket_path)) {
  sockaddr_un probe{};
  if (socket_path_.size() >= sizeof(probe.sun_path)) {
    throw std::system_error(ENAMETOOLONG, std::generic_category(), socket_path_);
  }
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "socket(AF_UNIX)");
}

JournalSink::~JournalSink() {
  if (fd_ >= 0) ::close(fd_);
}

void JournalSink::sink_it_(const spdlog::details::log_msg& msg) {
  const std::string text(msg.payload.data(), msg.payload.size());
  const std::string datagram = journal_message(identifier_, syslog_priority(msg.level), text);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::memcpy(addr.sun_path, socket_path_.data(), socket_path_.size());
  ssize_t sent = 0;
  do {
    sent = ::sendto(fd_, datagram.data(), datagram.size(), MSG_NOSIGNAL,
                    reinterpret_cast<const sockaddr*>(&addr), sizeof(addr));
  } while (sent < 0 && errno == EINTR);
}

}  // namespace calstand::daemon::service

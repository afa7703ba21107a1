#pragma once

#include <spdlog/sinks/base_sink.h>

#include <mutex>
#include <string>

namespace calstand::daemon::service {

/// The journal socket systemd-journald reads native messages on.
inline constexpr const char* kJournalSocket = "/run/systemd/journal/socket";

/// True when stderr is connected to the journal: $JOURNAL_STREAM ("DEVICE:INODE", set by
/// systemd for a service's stdout and stderr) names the file stderr is (systemd.exec(5)).
bool stderr_is_journal();

/// The journal message of one log line in journald's native protocol (systemd.io,
/// "Native Journal Protocol"): "KEY=VALUE\n" per field, or, for a value holding a newline,
/// "KEY\n", its length as 64-bit little endian, the value and "\n". Fields: MESSAGE, PRIORITY
/// (syslog's 0-7), SYSLOG_IDENTIFIER, and RUN, STEP, DEVICE from the thread's LogFields.
std::string journal_message(const std::string& identifier, int priority,
                            const std::string& message);

/// A spdlog sink that sends each line to the journal as a datagram of journal_message(), so
/// that its fields can be searched (`journalctl RUN=12`). A line the journal does not take
/// (too large, journald gone) is dropped: logging must never stop the daemon.
class JournalSink final : public spdlog::sinks::base_sink<std::mutex> {
 public:
  /// Opens a datagram socket; throws std::system_error when it cannot. `socket_path`: the
  /// journal's (tests give their own).
  explicit JournalSink(std::string identifier, std::string socket_path = kJournalSocket);
  ~JournalSink() override;
  JournalSink(const JournalSink&) = delete;
  JournalSink& operator=(const JournalSink&) = delete;

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override;
  void flush_() override {}

 private:
  std::string identifier_;
  std::string socket_path_;
  int fd_ = -1;
};

}  // namespace calstand::daemon::service

#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace calstand::daemon::service {

/// What a log line is about, beyond its text: the journal stores these as the fields RUN, STEP
/// (the step's index, as in the API and the database) and DEVICE (JournalSink), so that
/// `journalctl -u calstandd RUN=12` finds a run's lines. Kept per thread: the run thread sets
/// them as it goes, and every line it logs carries them.
struct LogFields {
  std::optional<std::int64_t> run;
  std::optional<std::size_t> step;
  std::optional<std::string> device;
};

/// The calling thread's fields (empty on a thread that set none).
LogFields& thread_log_fields();

/// Sets the given fields (those that are not empty) on the calling thread for its lifetime,
/// and puts back what was there before.
class ScopedLogFields {
 public:
  explicit ScopedLogFields(const LogFields& fields);
  ~ScopedLogFields();
  ScopedLogFields(const ScopedLogFields&) = delete;
  ScopedLogFields& operator=(const ScopedLogFields&) = delete;

 private:
  LogFields saved_;
};

}  // namespace calstand::daemon::service

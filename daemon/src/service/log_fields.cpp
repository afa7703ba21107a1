#include "daemon/service/log_fields.hpp"

namespace calstand::daemon::service {

LogFields& thread_log_fields() {
  thread_local LogFields fields;
  return fields;
}

ScopedLogFields::ScopedLogFields(const LogFields& fields) : saved_(thread_log_fields()) {
  LogFields& now = thread_log_fields();
  if (fields.run) now.run = fields.run;
  if (fields.step) now.step = fields.step;
  if (fields.device) now.device = fields.device;
}

ScopedLogFields::~ScopedLogFields() { thread_log_fields() = saved_; }

}  // namespace calstand::daemon::service

#pragma once

#include <stdexcept>
#include <string>

namespace calstand::fleet {

/// The central database said no, or could not be reached: connection refused or lost, a server
/// restarted, a schema of another version, a row-level security refusal. `operation()` names
/// what the fleet code was doing (`connect`, `copy runs`, ...); what() reads
/// `central: OPERATION: WHY`. A sync cut by such an error lost nothing: the batch in flight was
/// rolled back with its cursor, and the next sync resumes there.
///
/// A malformed address or password file is core::InputError instead.
class CentralError : public std::runtime_error {
 public:
  CentralError(std::string operation, const std::string& why)
      : std::runtime_error("central: " + operation + ": " + why),
        operation_(std::move(operation)) {}
  const std::string& operation() const { return operation_; }

 private:
  std::string operation_;
};

/// Call inside a catch block only: rethrows the exception in flight as a CentralError naming
/// `operation` (libpqxx and libpq failures, std::exception), and core::InputError and
/// CentralError as they are.
[[noreturn]] void rethrow_as_central(const std::string& operation);

}  // namespace calstand::fleet

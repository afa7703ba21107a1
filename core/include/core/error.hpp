#pragma once

#include <stdexcept>
#include <string>

namespace calstand::core {

/// Input that breaks a rule: a file, a JSON field, a CLI argument or a device frame. `where`
/// names the place (file and JSON path, or line), `what()` says where and why in one line.
class InputError : public std::runtime_error {
 public:
  InputError(std::string where, const std::string& why)
      : std::runtime_error(where.empty() ? why : where + ": " + why), where_(std::move(where)) {}
  const std::string& where() const { return where_; }

 private:
  std::string where_;
};

}  // namespace calstand::core

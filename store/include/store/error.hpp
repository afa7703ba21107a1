#pragma once

#include <stdexcept>
#include <string>

namespace calstand::store {

/// A storage operation failed (SQLite error, disk full, locked database, corrupt sample chunk,
/// a database from a newer calstand). `operation()` names what the store was doing, e.g.
/// `insert sample chunk`; what() reads `store: OPERATION: WHY`.
///
/// Bad user input (a malformed import folder, an unknown run id) is core::InputError instead.
class StoreError : public std::runtime_error {
 public:
  StoreError(std::string operation, const std::string& why)
      : std::runtime_error("store: " + operation + ": " + why), operation_(std::move(operation)) {}
  const std::string& operation() const { return operation_; }

 private:
  std::string operation_;
};

}  // namespace calstand::store

namespace calstand::store {

/// True for a failure of the storage itself (StoreError, or an SQLite error from a store
/// call): the database said no, not the caller's input or a bug.
bool is_storage_error(const std::exception& e);

}  // namespace calstand::store

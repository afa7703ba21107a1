#include "store/error.hpp"

#include <SQLiteCpp/Exception.h>

namespace calstand::store {

bool is_storage_error(const std::exception& e) {
  return dynamic_cast<const StoreError*>(&e) != nullptr ||
         dynamic_cast<const SQLite::Exception*>(&e) != nullptr;
}

}  // namespace calstand::store

#include "daemon/engine_command.hpp"

#include <utility>

namespace calstand::daemon {

void EngineCommandQueue::push(EngineCommand command) {
  std::lock_guard lock(mutex_);
  pending_.push_back(std::move(command));
}

std::vector<EngineCommand> EngineCommandQueue::take_all() {
  std::vector<EngineCommand> taken;
  std::lock_guard lock(mutex_);
  taken.swap(pending_);
  return taken;
}

void EngineCommandQueue::clear() {
  std::lock_guard lock(mutex_);
  pending_.clear();
}

}  // namespace calstand::daemon

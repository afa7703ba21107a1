#include "drivers/can_transport.hpp"

namespace calstand::drivers {

std::vector<can_filter> exact_id_filters(std::span<const canid_t> ids) {
  if (ids.empty()) return {can_filter{0, 0}};  // mask 0: every frame matches
  std::vector<can_filter> out;
  out.reserve(ids.size());
  for (canid_t id : ids) {
    // The flags in the mask make the match exact: an extended id never matches a standard
    // one with the same number, and remote frames (RTR set) never match.
    const bool extended = (id & CAN_EFF_FLAG) != 0;
    out.push_back({id & (CAN_EFF_FLAG | CAN_EFF_MASK),
                   CAN_EFF_FLAG | CAN_RTR_FLAG | (extended ? CAN_EFF_MASK : CAN_SFF_MASK)});
  }
  return out;
}

bool passes_filters(canid_t frame_id, std::span<const can_filter> filters) {
  for (const auto& f : filters) {
    if ((frame_id & f.can_mask) == (f.can_id & f.can_mask)) return true;
  }
  return false;
}

}  // namespace calstand::drivers

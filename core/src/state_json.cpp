#include "core/state_json.hpp"

#include <string>

namespace calstand::core {

nlohmann::json to_json(const AxisState& axis) {
  nlohmann::json j = {{"angle_deg", axis.angle_deg},
                      {"rate_dps", axis.rate_dps},
                      {"mode", std::string(to_string(axis.mode))},
                      {"in_position", axis.in_position},
                      {"fault", axis.fault}};
  if (axis.fault) j["fault_text"] = axis.fault_text;
  return j;
}

nlohmann::json to_json(const TableState& table) {
  return {{"time_s", table.time_s},
          {"outer", to_json(table.outer)},
          {"inner", to_json(table.inner)},
          {"link_lost", table.link_lost}};
}

nlohmann::json to_json(const ChamberState& chamber) {
  nlohmann::json j = {{"time_s", chamber.time_s},
                      {"air_c", chamber.air_temperature_c},
                      {"setpoint_c", chamber.setpoint_c},
                      {"mode", std::string(to_string(chamber.mode))},
                      {"fault", chamber.fault}};
  if (chamber.fault) j["fault_text"] = chamber.fault_text;
  j["link_lost"] = chamber.link_lost;
  return j;
}

}  // namespace calstand::core

#pragma once

#include <nlohmann/json.hpp>

#include "core/chamber_state.hpp"
#include "core/table_state.hpp"

namespace calstand::core {

/// The one JSON shape of the station's device states, wherever calstand shows them (calstandd's
/// GET /station and live telemetry, `calstand device ... --json`): units in the keys;
/// `fault_text` only while `fault` is set. schemas/api.md documents it.
/// {"angle_deg", "rate_dps", "mode", "in_position", "fault", "fault_text"?}
nlohmann::json to_json(const AxisState& axis);
/// {"time_s", "outer": AXIS, "inner": AXIS, "link_lost"}
nlohmann::json to_json(const TableState& table);
/// {"time_s", "air_c", "setpoint_c", "mode", "fault", "fault_text"?, "link_lost"}
nlohmann::json to_json(const ChamberState& chamber);

}  // namespace calstand::core

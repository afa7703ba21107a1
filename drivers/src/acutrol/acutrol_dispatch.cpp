#include <fmt/format.h>

#include "drivers/acutrol_server.hpp"

namespace calstand::drivers {

using acutrol::CommandKind;

namespace {

std::string ack(const Refusal& refusal) {
  return refusal ? acutrol::format_error(refusal->code, refusal->text) : std::string("OK");
}

}  // namespace

std::string handle_command_line(std::string_view line, TableServerBackend& backend) {
  const auto parsed = acutrol::parse_command(line);
  if (!parsed.command) return acutrol::format_error(parsed.error.code, parsed.error.text);
  const auto& c = *parsed.command;
  switch (c.kind) {
    case CommandKind::kIdentify:
      return acutrol::sanitize_text(backend.identity(), acutrol::kMaxLineBytes);
    case CommandKind::kModeRate:
      return ack(backend.select_mode(c.axis, acutrol::WireMode::kRate));
    case CommandKind::kModePosition:
      return ack(backend.select_mode(c.axis, acutrol::WireMode::kPosition));
    case CommandKind::kDemandRate:
      return ack(backend.demand_rate(c.axis, c.value));
    case CommandKind::kDemandPosition:
      return ack(backend.demand_position(c.axis, c.value));
    case CommandKind::kModeSine:
      return ack(backend.select_mode(c.axis, acutrol::WireMode::kSine));
    case CommandKind::kDemandSine:
      return ack(backend.demand_sine(c.axis, c.value, c.value2));
    case CommandKind::kReadPosition:
      return acutrol::format_number(backend.report(c.axis).angle_deg);
    case CommandKind::kReadRate:
      return acutrol::format_number(backend.report(c.axis).rate_dps);
    case CommandKind::kReadStatus:
      return acutrol::format_status(backend.report(c.axis).status);
    case CommandKind::kInterlockQuery:
      return acutrol::format_interlock(backend.interlock(c.axis));
    case CommandKind::kInterlockClose:
      return ack(backend.close_interlock(c.axis));
    case CommandKind::kLimit:
      return ack(backend.set_limits(c.axis, c.value, c.value2));
    case CommandKind::kStop:
      backend.stop(c.axis);
      return "OK";
  }
  return acutrol::format_error(acutrol::ErrorCode::kController, "command not implemented");
}

}  // namespace calstand::drivers

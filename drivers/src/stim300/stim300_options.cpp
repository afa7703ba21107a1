// Reads `connection.stim300` (stim300_options.hpp).
#include "drivers/stim300_options.hpp"

#include <fmt/format.h>

#include "core/error.hpp"

namespace calstand::drivers::stim300 {

Stim300Options parse_stim300_options(const WireFormatSettings& settings) {
  Stim300Options o;
  const auto& j = settings.options;
  if (!j.is_object()) throw core::InputError(settings.where, "must be an object");
  const auto field = [&](const char* key) { return settings.where + "." + key; };
  for (const auto& [key, value] : j.items()) {
    if (key == "datagram") {
      const auto name = value.is_string() ? value.get<std::string>() : std::string();
      if (name == "auto") continue;
      o.datagram = datagram_id_from_name(name);
      if (!o.datagram) {
        throw core::InputError(field("datagram"),
                               "not a STIM300 normal-mode datagram this driver reads: give "
                               "0x90..0x94, 0xA5..0xA7, a name such as \"rate_acc_incl\", or "
                               "\"auto\"");
      }
    } else if (key == "accel_range_g") {
      const int g = value.is_number_integer() ? value.get<int>() : 0;
      if (g != 5 && g != 10 && g != 30 && g != 80) {
        throw core::InputError(field("accel_range_g"), "must be 5, 10, 30 or 80");
      }
      o.accel_range_g = g;
    } else if (key == "gyro_output") {
      const auto s = value.is_string() ? value.get<std::string>() : std::string();
      if (s != "rate" && s != "increment") {
        throw core::InputError(field("gyro_output"), "must be \"rate\" or \"increment\"");
      }
      o.gyro_output = s == "rate" ? GyroOutput::kAngularRate : GyroOutput::kIncrement;
    } else if (key == "accel_output") {
      const auto s = value.is_string() ? value.get<std::string>() : std::string();
      if (s != "acceleration" && s != "increment") {
        throw core::InputError(field("accel_output"), "must be \"acceleration\" or \"increment\"");
      }
      o.accel_output = s == "acceleration" ? AccelOutput::kAcceleration : AccelOutput::kIncrement;
    } else if (key == "termination") {
      if (!value.is_boolean())
        throw core::InputError(field("termination"), "must be true or false");
      o.termination = value.get<bool>();
    } else if (key == "rate_check") {
      if (!value.is_boolean()) throw core::InputError(field("rate_check"), "must be true or false");
      o.rate_check = value.get<bool>();
    } else {
      throw core::InputError(field(key.c_str()), "unknown option of format stim300");
    }
  }
  return o;
}

}  // namespace calstand::drivers::stim300

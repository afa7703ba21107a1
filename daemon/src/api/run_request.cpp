#include "daemon/api/run_request.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "procedures/library.hpp"

namespace calstand::daemon::api {

RunRequest parse_run_request(const nlohmann::json& body) {
  std::vector<procedures::Violation> violations;
  if (!body.is_object()) {
    throw procedures::ProcedureError("request", {{"", "the body must be a JSON object"}});
  }
  for (const auto& [key, value] : body.items()) {
    if (key != "procedure" && key != "parameters" && key != "units") {
      violations.push_back({key, "unknown field (expected procedure, parameters, units)"});
    }
  }
  procedures::Overrides overrides;
  if (const auto p = body.find("parameters"); p != body.end()) {
    if (!p->is_object()) {
      violations.push_back({"parameters", "must be an object of parameter values"});
    } else {
      for (const auto& [k, v] : p->items()) overrides[k] = v;
    }
  }
  UnitSerials units;
  if (const auto u = body.find("units"); u != body.end()) {
    if (!u->is_object()) {
      violations.push_back({"units", "must be an object of serials by IMU name"});
    } else {
      for (const auto& [imu, serial] : u->items()) {
        if (!serial.is_string() || serial.get<std::string>().empty()) {
          violations.push_back({"units." + imu, "must be a non-empty serial string"});
        } else {
          units[imu] = serial.get<std::string>();
        }
      }
    }
  }
  const auto proc = body.find("procedure");
  if (proc == body.end()) {
    violations.push_back({"procedure", "is required (a library name or a procedure document)"});
  } else if (!proc->is_string() && !proc->is_object()) {
    violations.push_back({"procedure", "must be a library name or a procedure document"});
  } else if (proc->is_string() && !procedures::library_text(proc->get<std::string>())) {
    violations.push_back(
        {"procedure", fmt::format("'{}' is not a library procedure ({})", proc->get<std::string>(),
                                  fmt::join(procedures::library_names(), ", "))});
  }
  if (!violations.empty()) throw procedures::ProcedureError("request", std::move(violations));

  RunRequest out;
  if (proc->is_string()) {
    out.procedure = procedures::load_procedure(proc->get<std::string>());
  } else {
    out.procedure = procedures::parse_procedure(proc->dump(2), "request.procedure");
  }
  out.overrides = std::move(overrides);
  out.units = std::move(units);
  return out;
}

}  // namespace calstand::daemon::api

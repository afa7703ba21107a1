#pragma once

#include <nlohmann/json.hpp>

#include "daemon/campaign.hpp"
#include "procedures/procedure.hpp"

namespace calstand::daemon::api {

/// A `POST /runs` body made into what the run service plans.
struct RunRequest {
  procedures::Procedure procedure;
  procedures::Overrides overrides;
  UnitSerials units;  ///< serials given for the run's units, by IMU name
};

/// Reads a `POST /runs` body: `{"procedure": NAME | {procedure document}, "parameters": {...},
/// "units": {"imu0": "SN1234", ...}}` ("units" optional).
/// NAME is a library procedure only (the daemon never reads a file a client names); an inline
/// document is parsed and checked like a procedure file named `request.procedure`.
/// Throws procedures::ProcedureError listing every violation (paths such as `procedure`,
/// `parameters.capture_s`, `procedure.steps[2].kind`).
RunRequest parse_run_request(const nlohmann::json& body);

}  // namespace calstand::daemon::api

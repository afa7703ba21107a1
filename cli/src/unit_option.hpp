#pragma once
// `--unit NAME=SERIAL`, given to `calstand run` and `calstand submit` once per unit.

#include <string>
#include <vector>

#include "daemon/campaign.hpp"

namespace calstand::cli {

/// Reads `NAME=SERIAL` arguments into serials by IMU name. Throws core::InputError naming
/// `--unit` and the argument when one has no `=`, an empty side, or names an IMU twice.
daemon::UnitSerials parse_unit_options(const std::vector<std::string>& args);

}  // namespace calstand::cli

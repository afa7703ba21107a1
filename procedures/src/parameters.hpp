#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "procedures/procedure.hpp"

namespace calstand::procedures::detail {

/// Defaults with every acceptable override applied; each rejected override is appended to
/// `out` (path `--set NAME`) and its default kept.
std::map<std::string, nlohmann::json> resolve_parameters_collecting(const Procedure& procedure,
                                                                    const Overrides& overrides,
                                                                    std::vector<Violation>& out);

}  // namespace calstand::procedures::detail

#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::procedures {

/// Names of the procedures shipped in procedures/library/ and compiled into the binary
/// (`six-position` for library/six-position.json), sorted.
std::vector<std::string> library_names();

/// The text of library procedure `name`, or nullopt when there is none by that name.
std::optional<std::string_view> library_text(std::string_view name);

}  // namespace calstand::procedures

#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::core {

/// Optimal string alignment distance: edits, with a swap of neighbours counting as one.
std::size_t edit_distance(std::string_view a, std::string_view b);

/// The candidate closest to `word` within `max_distance` edits, or "" when none is. A candidate
/// no longer than the distance shares nothing with the word, so it is no suggestion.
std::string closest_name(std::string_view word, const std::vector<std::string_view>& candidates,
                         std::size_t max_distance = 2);

}  // namespace calstand::core

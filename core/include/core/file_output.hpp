#pragma once
// Files calstand writes for a user (records, certificates, exports, reports): whole or not at
// all, so that a full disk or a killed process never leaves half a file under the final name.

#include <string>
#include <string_view>

namespace calstand::core {

/// Writes `text` to `path`: into a temporary beside it (one file system, so the rename is atomic;
/// named for this process, so two writers of one target do not share it), then renamed over it.
/// The temporary is removed whatever fails. Throws InputError naming `path` when it cannot be
/// written; the file then keeps what it held before.
void write_file_whole(const std::string& path, std::string_view text);

}  // namespace calstand::core

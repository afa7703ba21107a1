#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace calstand::daemon::api {

inline constexpr std::size_t kUstarBlock = 512;

/// The 512-byte ustar header of a regular file `name` of `size` bytes (mode 0644, owner 0/0,
/// modification time `mtime_s` [Unix s]). Throws std::invalid_argument for a name the format or
/// the rules of UstarWriter do not admit.
std::string ustar_header(std::string_view name, std::uint64_t size, std::int64_t mtime_s = 0);
/// The zero bytes that fill a file of `size` bytes up to whole blocks.
std::size_t ustar_padding(std::uint64_t size);

/// Builds a POSIX ustar archive in memory (regular files only), so that an export can be sent
/// as one download without running `tar`. Names must be relative, at most 100 bytes, without
/// "..": the archive's names are chosen by the daemon, never by a client.
class UstarWriter {
 public:
  /// Appends a regular file (mode 0644, owner 0/0, modification time `mtime_s` [Unix s]).
  /// Throws std::invalid_argument for a name the format or the rules above do not admit.
  void add_file(std::string_view name, std::string_view content, std::int64_t mtime_s = 0);
  /// The archive: the files, then the two zero blocks that end it.
  std::string finish() &&;

 private:
  std::string out_;
};

}  // namespace calstand::daemon::api

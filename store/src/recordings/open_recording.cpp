// Which recording a path holds, and its reader: the one place that knows every format
// (recording_common.cpp is what the readers share; each reader its own file).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

#include "core/error.hpp"
#include "recording_detail.hpp"
#include "store/recording_reader.hpp"

namespace calstand::store {
namespace {

bool starts_with_bytes(const std::filesystem::path& file, std::string_view magic) {
  std::FILE* f = std::fopen(file.string().c_str(), "rb");
  if (f == nullptr) return false;
  std::string head(magic.size(), '\0');
  const std::size_t got = std::fread(head.data(), 1, head.size(), f);
  std::fclose(f);
  return got == magic.size() && head == magic;
}

bool has_euroc_imu(const std::filesystem::path& mav0) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(mav0, ec)) {
    if (e.path().filename().string().starts_with("imu") &&
        std::filesystem::is_regular_file(e.path() / "data.csv")) {
      return true;
    }
  }
  return false;
}

}  // namespace

std::optional<std::string> detect_recording_format(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  using namespace recordings;
  if (fs::is_directory(path)) {
    if (fs::is_regular_file(path / "meta.json")) return "calstand-import";
    if (fs::is_regular_file(path / "metadata.yaml")) return "ros2-bag";
    if (fs::is_directory(path / "mav0") && has_euroc_imu(path / "mav0")) return "euroc";
    if (path.filename() == "mav0" && has_euroc_imu(path)) return "euroc";
    return std::nullopt;
  }
  if (!fs::is_regular_file(path)) return std::nullopt;
  if (starts_with_bytes(path, kMcapMagic)) return "mcap";
  if (starts_with_bytes(path, kRos1BagVersion)) return "ros1-bag";
  if (starts_with_bytes(path, kSqliteMagic)) return "ros2-bag";
  return std::nullopt;
}

std::unique_ptr<RecordingReader> open_recording(const std::filesystem::path& path) {
  using namespace recordings;
  const auto format = detect_recording_format(path);
  if (!std::filesystem::exists(path)) throw core::InputError(path.string(), "no such file");
  if (!format || *format == "calstand-import") {
    throw core::InputError(
        path.string(),
        "not a recording calstand reads: a MCAP file, a ROS 1 bag (#ROSBAG V2.0), a ROS 2 bag "
        "folder (metadata.yaml) or .db3 file, a EuRoC/TUM-VI folder (mav0/imu0/data.csv), or a "
        "calstand-import folder (meta.json and samples.csv: a CSV of another tool imports once "
        "a meta.json describes its columns and units, docs/import.md)");
  }
  if (*format == "mcap") return make_message_recording(open_mcap(path));
  if (*format == "ros1-bag") return make_message_recording(open_ros1_bag(path));
  if (*format == "ros2-bag") return make_message_recording(open_ros2_bag(path));
  return open_euroc(path);
}

}  // namespace calstand::store

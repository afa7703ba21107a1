#pragma once
// Reading IMU recordings that other tools write (ROS 1 bags, ROS 2 bags, MCAP, EuRoC/TUM-VI),
// chunk by chunk in constant memory. One source file per format under store/src/recordings/;
// the specifications each follows are cited there and in docs/import.md.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace calstand::store {

/// One IMU message as recorded, in the message's own units.
struct ImuRecord {
  double t_s = 0.0;  ///< header stamp: sec + nanosec * 1e-9 [s] (not the bag's receive time)
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();  ///< angular_velocity [rad/s]
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();  ///< linear_acceleration [m/s^2]
};

/// A topic (a MCAP channel, a bag connection, a EuRoC sensor folder).
struct TopicInfo {
  std::string name;         ///< e.g. "/imu/data"; EuRoC: "/imu0" for mav0/imu0
  std::string type;         ///< e.g. "sensor_msgs/msg/Imu", "sensor_msgs/Imu"
  std::string encoding;     ///< "cdr", "ros1" or "csv"
  std::uint64_t count = 0;  ///< messages
  double rate_hz = 0.0;     ///< (count - 1) / recorded time span; 0 when unknown
  bool imu = false;         ///< a sensor_msgs Imu this reader decodes
};

/// A recording opened for reading. Not thread-safe; one reader per thread.
///
/// Errors are core::InputError whose where() names the file and, for content, the byte
/// offset (`bag.mcap: byte 1234`) and whose message says why (truncated, CRC mismatch, unknown
/// compression or encoding, a message that does not decode).
class RecordingReader {
 public:
  virtual ~RecordingReader() = default;
  /// "mcap", "ros2-bag", "ros1-bag" or "euroc".
  virtual std::string format() const = 0;
  /// Every topic with its message count and rate. Taken from the recording's index or summary
  /// when it has one; otherwise by reading the whole recording once.
  virtual std::vector<TopicInfo> topics() = 0;
  /// Chooses the topic read() yields (a name topics() lists); throws InputError when it is
  /// absent or not an IMU topic. Starts reading from the beginning.
  virtual void select(const std::string& topic) = 0;
  /// The selected topic (name, type, encoding; count and rate as topics() has them), once
  /// select() or read() has found it.
  virtual std::optional<TopicInfo> selected() const = 0;
  /// Replaces `batch` with the next samples of the selected topic, in recorded order, at most
  /// about `max` of them (one chunk's worth at a time); false (and `batch` empty) at the end.
  virtual bool read(std::vector<ImuRecord>& batch, std::size_t max) = 0;
  /// The file being read and the byte offset reached, for messages and progress.
  virtual std::string position() const = 0;
  /// Fraction of the input consumed, in [0, 1] (for a progress bar).
  virtual double progress() const = 0;
};

/// Which kind of input `path` is, from its content: "mcap" (a file starting with the MCAP
/// magic), "ros1-bag" ("#ROSBAG V2.0"), "ros2-bag" (a folder with metadata.yaml, or a sqlite3
/// file with rosbag2's topics and messages tables), "euroc" (a folder with mav0/imu*/data.csv,
/// or the mav0 folder itself), "calstand-import" (a folder with meta.json), or none.
std::optional<std::string> detect_recording_format(const std::filesystem::path& path);

/// Opens a recording of a kind detect_recording_format() names (not "calstand-import").
/// Throws core::InputError naming the path when it is none of them, or cannot be read.
std::unique_ptr<RecordingReader> open_recording(const std::filesystem::path& path);

}  // namespace calstand::store

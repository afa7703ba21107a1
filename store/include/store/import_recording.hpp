#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "store/database.hpp"
#include "store/recording_reader.hpp"

namespace calstand::store {

/// Options of import_recording().
struct RecordingImportOptions {
  /// The IMU topic; empty: the recording's only IMU topic.
  std::string topic;
  /// The site (a recording carries none). Latitude and height come together; without them
  /// kDefaultLatitudeDeg and kDefaultHeightM are used and the result says so.
  std::optional<double> latitude_deg;
  std::optional<double> height_m;
  /// Measured local gravity [m/s^2]; normal gravity at the site when absent.
  std::optional<double> gravity_mps2;
  /// Samples per batch written (and per read).
  std::size_t batch = 8192;
  /// Called after each batch with the fraction of the input read and the samples so far.
  std::function<void(double fraction, std::uint64_t samples)> progress;
};

/// The site used when none is given: 45 deg latitude at sea level (normal gravity there is
/// 9.80620 m/s^2, within 0.03 % of any site below 1 km between 35 and 55 deg).
inline constexpr double kDefaultLatitudeDeg = 45.0;
inline constexpr double kDefaultHeightM = 0.0;

/// What import_recording() created and found.
struct RecordingImportResult {
  std::int64_t run = 0;
  std::string format;  ///< detect_recording_format()'s name
  std::string path;
  TopicInfo topic;                ///< the topic imported (count and rate as indexed)
  std::vector<TopicInfo> topics;  ///< every topic, when they were listed
  std::uint64_t samples = 0;
  double latitude_deg = 0.0;
  double height_m = 0.0;
  double gravity_mps2 = 0.0;
  /// "given", "normal gravity at the given site", or which default was used.
  std::string site_source;
  double first_s = 0.0;            ///< first header stamp [s]
  double last_s = 0.0;             ///< last header stamp [s]
  double period_s = 0.0;           ///< median interval between stamps (first 1000) [s]
  double rate_hz = 0.0;            ///< 1 / period_s (meta's sample_rate_hz)
  std::uint64_t gaps = 0;          ///< intervals longer than 1.5 periods
  double gap_time_s = 0.0;         ///< time missing in them (interval - period, summed) [s]
  double largest_gap_s = 0.0;      ///< the longest interval of a gap [s]
  double largest_gap_at_s = 0.0;   ///< stamp of the sample after it [s]
  std::uint64_t out_of_order = 0;  ///< stamps earlier than the one before
  std::uint64_t duplicates = 0;    ///< stamps equal to the one before
  nlohmann::ordered_json to_json() const;
};

/// Imports the IMU topic of a recording (store/recording_reader.hpp: MCAP, ROS 1 or ROS 2
/// bag, EuRoC/TUM-VI folder) as a `calstand-import/2` run without table: one step
/// "recording" (`{"mode": "recording", "orientation": "unknown"}`), the samples of device
/// "imu0" in recorded order with the header stamp as their time, the angular rate converted
/// from rad/s to deg/s exactly as a /2 samples.csv in rad/s is, no temperature. The run's
/// meta.json is the /2 one such a folder would have (site with gravity, measured
/// sample_rate_hz, units rad/s and m/s^2); its parameters hold the source and the topic.
///
/// Streams in constant memory: batches read, converted and written as they come, in one
/// transaction, so that a failure (an InputError of the recording, found mid-way) leaves
/// nothing. Throws core::InputError naming the file, position and reason (not a recording,
/// truncated, CRC mismatch, unknown compression or encoding, undecodable message, no or an
/// ambiguous IMU topic (listing the IMU topics with counts and rates), a topic that is not an
/// IMU, no samples), or for the site (latitude without height, values out of range); StoreError
/// when writing fails.
RecordingImportResult import_recording(Database& db, const std::filesystem::path& path,
                                       const RecordingImportOptions& options = {});

}  // namespace calstand::store

#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"
#include "store/database.hpp"
#include "store/sample_codec.hpp"

namespace calstand::store {

/// Where a chunk belongs, from its table row.
struct ChunkInfo {
  std::int64_t id = 0;
  std::int64_t step_id = 0;
  int attempt = 0;
  std::string device;
  double first_receive_time_s = 0.0;  ///< [s] station clock
  double last_receive_time_s = 0.0;   ///< [s] station clock
  std::uint32_t count = 0;
  SampleEncoding encoding = SampleEncoding::kCompact;
};

/// The attempt whose samples are step `index`'s data: its good attempt when completed, else the
/// latest attempt with samples; none when it has no samples. Throws core::InputError when the
/// step does not exist, StoreError on SQL failure.
std::optional<int> data_attempt(Database& db, std::int64_t run, std::size_t index);

/// Calls `fn` for each chunk of `device` in step `index` of `run` (the data attempt, see
/// data_attempt()), in the order written, with the decoded samples. Throws as data_attempt(),
/// and StoreError on a corrupt chunk.
void for_each_chunk(
    Database& db, std::int64_t run, std::size_t index, const std::string& device,
    const std::function<void(const ChunkInfo&, std::span<const core::ImuSample>)>& fn);

/// Samples decoded from sample chunks by this process so far (every database and thread): how
/// often captures are read, for the tests and benchmarks that check an analysis reads a long
/// capture once. Only ever grows.
std::uint64_t samples_decoded();

/// Every sample of `device` in step `index` of `run`, in the order written (empty when none).
std::vector<core::ImuSample> read_samples(Database& db, std::int64_t run, std::size_t index,
                                          const std::string& device);

/// Device names with samples in `run`, sorted.
std::vector<std::string> sample_devices(Database& db, std::int64_t run);

/// A row of table step_means: per step attempt and device, over its samples. A NULL column
/// reads NaN: the temperature of samples without one (an import without temp_c), the spread of
/// a single sample.
struct StepMean {
  std::size_t step_index = 0;
  int attempt = 0;
  std::string device;
  std::int64_t count = 0;
  double first_receive_time_s = 0.0;                       ///< [s]
  double last_receive_time_s = 0.0;                        ///< [s]
  Eigen::Vector3d gyro_dps = Eigen::Vector3d::Zero();      ///< mean [deg/s]
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();    ///< mean [m/s^2]
  double temperature_c = 0.0;                              ///< mean [degC]
  Eigen::Vector3d gyro_std_dps = Eigen::Vector3d::Zero();  ///< sample standard deviation
  Eigen::Vector3d accel_std_mps2 = Eigen::Vector3d::Zero();
  double temperature_std_c = 0.0;
};

/// The step means of the data attempts of `run`'s completed steps, by step index then device.
std::vector<StepMean> read_step_means(Database& db, std::int64_t run);

}  // namespace calstand::store

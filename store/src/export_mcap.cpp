// A run as MCAP (issue 32: a corrected run back into a ROS pipeline), written from the MCAP
// specification (mcap.dev/spec) as store/src/recordings/mcap_reader.cpp reads it: one ros2msg
// schema, one cdr channel /imu/data, messages in zstd chunks of about 1 MiB of records with
// their CRC-32, Data End, a summary (schema, channel, statistics) and the footer.

#include <fmt/format.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>

#include "core/error.hpp"
#include "recordings/recording_detail.hpp"
#include "store/import_export.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"
#include "store/step_data.hpp"

namespace calstand::store {
namespace {

constexpr std::size_t kExportChunkBytes = std::size_t{1} << 20;
constexpr int kExportZstdLevel = 3;
constexpr std::uint16_t kExportSchemaId = 1;
constexpr std::uint16_t kExportChannelId = 1;
// sensor_msgs/msg/Imu's definition as a ros2msg schema (common_interfaces).
constexpr std::string_view kImuSchemaText =
    "std_msgs/Header header\n"
    "geometry_msgs/Quaternion orientation\n"
    "float64[9] orientation_covariance\n"
    "geometry_msgs/Vector3 angular_velocity\n"
    "float64[9] angular_velocity_covariance\n"
    "geometry_msgs/Vector3 linear_acceleration\n"
    "float64[9] linear_acceleration_covariance\n";

class McapBytes {
 public:
  void u8(std::uint8_t v) { raw(&v, 1); }
  void u16(std::uint16_t v) { raw(&v, 2); }
  void u32(std::uint32_t v) { raw(&v, 4); }
  void u64(std::uint64_t v) { raw(&v, 8); }
  void f64(double v) { raw(&v, 8); }
  void str(std::string_view s) {
    u32(static_cast<std::uint32_t>(s.size()));
    raw(s.data(), s.size());
  }
  void raw(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    bytes.insert(bytes.end(), b, b + n);
  }
  /// A record: opcode, length, then `content`.
  void record(std::uint8_t op, const McapBytes& content) {
    u8(op);
    u64(content.bytes.size());
    raw(content.bytes.data(), content.bytes.size());
  }
  std::vector<std::uint8_t> bytes;
};

McapBytes schema_record() {
  McapBytes c;
  c.u16(kExportSchemaId);
  c.str("sensor_msgs/msg/Imu");
  c.str("ros2msg");
  c.str(kImuSchemaText);
  McapBytes r;
  r.record(0x03, c);
  return r;
}

McapBytes channel_record() {
  McapBytes c;
  c.u16(kExportChannelId);
  c.u16(kExportSchemaId);
  c.str("/imu/data");
  c.str("cdr");
  c.u32(0);  // metadata: empty map
  McapBytes r;
  r.record(0x04, c);
  return r;
}

class McapFileOut {
 public:
  explicit McapFileOut(const std::filesystem::path& path) : path_(path) {
    f_ = std::fopen(path.string().c_str(), "wb");
    if (f_ == nullptr) throw std::runtime_error(path.string() + ": cannot write the file");
  }
  ~McapFileOut() {
    if (f_ != nullptr) std::fclose(f_);
  }
  McapFileOut(const McapFileOut&) = delete;
  McapFileOut& operator=(const McapFileOut&) = delete;
  void write(const std::vector<std::uint8_t>& b) {
    if (std::fwrite(b.data(), 1, b.size(), f_) != b.size()) {
      throw std::runtime_error(path_.string() + ": cannot write the file (disk full?)");
    }
    offset_ += b.size();
  }
  void close() {
    const int rc = std::fclose(f_);
    f_ = nullptr;
    if (rc != 0) throw std::runtime_error(path_.string() + ": cannot write the file");
  }
  std::uint64_t offset() const { return offset_; }

 private:
  std::filesystem::path path_;
  std::FILE* f_ = nullptr;
  std::uint64_t offset_ = 0;
};

}  // namespace

void export_run_mcap(Database& db, std::int64_t run, const std::filesystem::path& file,
                     const ExportOptions& options) {
  RunStore runs(db);
  const RunRecord record = runs.load_run(run);
  const std::string device = choose_device(db, run, options.device);
  const std::filesystem::path part = file.string() + ".part";
  try {
    McapFileOut out(part);
    McapBytes head;
    head.raw(recordings::kMcapMagic.data(), recordings::kMcapMagic.size());
    McapBytes header;
    header.str("ros2");
    header.str("calstand");
    head.record(0x01, header);
    out.write(head.bytes);

    McapBytes records = schema_record();
    {
      const McapBytes ch = channel_record();
      records.raw(ch.bytes.data(), ch.bytes.size());
    }
    std::uint64_t count = 0;
    std::uint64_t first_ns = std::numeric_limits<std::uint64_t>::max();
    std::uint64_t last_ns = 0;
    std::uint64_t chunk_first = std::numeric_limits<std::uint64_t>::max();
    std::uint64_t chunk_last = 0;
    std::uint64_t chunks = 0;
    std::vector<std::uint8_t> packed;
    const auto flush = [&] {
      if (records.bytes.empty()) return;
      packed.resize(ZSTD_compressBound(records.bytes.size()));
      const std::size_t n = ZSTD_compress(packed.data(), packed.size(), records.bytes.data(),
                                          records.bytes.size(), kExportZstdLevel);
      if (ZSTD_isError(n) != 0) {
        throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
      }
      McapBytes c;
      c.u64(chunk_first == std::numeric_limits<std::uint64_t>::max() ? 0 : chunk_first);
      c.u64(chunk_last);
      c.u64(records.bytes.size());
      c.u32(recordings::crc32(records.bytes));
      c.str("zstd");
      c.u64(n);
      c.raw(packed.data(), n);
      McapBytes r;
      r.record(0x06, c);
      out.write(r.bytes);
      records.bytes.clear();
      chunk_first = std::numeric_limits<std::uint64_t>::max();
      chunk_last = 0;
      ++chunks;
    };
    constexpr double kRadPerDeg = std::numbers::pi / 180.0;
    for (const StepRecord& step : record.steps) {
      if (step.status != StepStatus::kCompleted) continue;
      for_each_chunk(
          db, run, step.index, device,
          [&](const ChunkInfo&, std::span<const core::ImuSample> samples) {
            for (const core::ImuSample& s : samples) {
              const double t = s.receive_time_s;
              auto sec = static_cast<std::int64_t>(std::floor(t));
              auto nsec =
                  static_cast<std::int64_t>(std::llround((t - static_cast<double>(sec)) * 1e9));
              if (nsec >= 1000000000) {
                ++sec;
                nsec -= 1000000000;
              }
              const std::uint64_t ns =
                  static_cast<std::uint64_t>(std::max<std::int64_t>(sec, 0)) * 1000000000ULL +
                  static_cast<std::uint64_t>(nsec);
              McapBytes m;
              m.u16(kExportChannelId);
              m.u32(static_cast<std::uint32_t>(count));
              m.u64(ns);
              m.u64(ns);
              // CDR: encapsulation, header (stamp, frame_id "imu" + NUL; 16 bytes,
              // so no padding before the float64s), then 37 float64.
              const std::uint8_t encapsulation[4] = {0x00, 0x01, 0x00, 0x00};
              m.raw(encapsulation, 4);
              m.u32(static_cast<std::uint32_t>(static_cast<std::int32_t>(sec)));
              m.u32(static_cast<std::uint32_t>(nsec));
              m.str(std::string_view("imu\0", 4));  // 16 bytes: aligned for 8
              for (const double q : {0.0, 0.0, 0.0, 1.0}) m.f64(q);
              // Orientation not given (REP 145): covariance[0] = -1.
              m.f64(-1.0);
              for (int k = 0; k < 8; ++k) m.f64(0.0);
              for (int k = 0; k < 3; ++k) m.f64(s.gyro_dps[k] * kRadPerDeg);
              for (int k = 0; k < 9; ++k) m.f64(0.0);
              for (int k = 0; k < 3; ++k) m.f64(s.accel_mps2[k]);
              for (int k = 0; k < 9; ++k) m.f64(0.0);
              records.record(0x05, m);
              ++count;
              first_ns = std::min(first_ns, ns);
              last_ns = std::max(last_ns, ns);
              chunk_first = std::min(chunk_first, ns);
              chunk_last = std::max(chunk_last, ns);
              if (records.bytes.size() >= kExportChunkBytes) flush();
            }
          });
    }
    flush();
    McapBytes tail;
    McapBytes data_end;
    data_end.u32(0);  // data section CRC not computed
    tail.record(0x0F, data_end);
    const std::uint64_t summary_start = out.offset() + tail.bytes.size();
    const McapBytes schema = schema_record();
    const McapBytes channel = channel_record();
    tail.raw(schema.bytes.data(), schema.bytes.size());
    tail.raw(channel.bytes.data(), channel.bytes.size());
    McapBytes stats;
    stats.u64(count);
    stats.u16(1);
    stats.u32(1);
    stats.u32(0);
    stats.u32(0);
    stats.u32(static_cast<std::uint32_t>(chunks));
    stats.u64(count > 0 ? first_ns : 0);
    stats.u64(last_ns);
    stats.u32(2 + 8);  // channel_message_counts: one entry
    stats.u16(kExportChannelId);
    stats.u64(count);
    tail.record(0x0B, stats);
    McapBytes footer;
    footer.u64(summary_start);
    footer.u64(0);  // no summary offset records
    footer.u32(0);  // summary CRC not computed
    tail.record(0x02, footer);
    tail.raw(recordings::kMcapMagic.data(), recordings::kMcapMagic.size());
    out.write(tail.bytes);
    out.close();
    std::filesystem::rename(part, file);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(part, ec);
    throw;
  }
}

}  // namespace calstand::store

#include <bzlib.h>
#include <fmt/format.h>
#include <isa-l/crc.h>
#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <limits>
#include <map>
#include <memory>

#include "recording_detail.hpp"

namespace calstand::store {
namespace recordings {

std::string at_byte(const std::string& file, std::uint64_t offset) {
  return fmt::format("{}: byte {}", file, offset);
}

InputFile::InputFile(const std::filesystem::path& path) : name_(path.string()) {
  f_ = std::fopen(name_.c_str(), "rb");
  if (f_ == nullptr) {
    throw core::InputError(name_, fmt::format("cannot open the file ({})", std::strerror(errno)));
  }
  std::error_code ec;
  size_ = std::filesystem::file_size(path, ec);
  if (ec) throw core::InputError(name_, "cannot read the file's size: " + ec.message());
  // Large reads: the readers take whole chunks at a time.
  std::setvbuf(f_, nullptr, _IOFBF, std::size_t{1} << 20);
}

InputFile::~InputFile() {
  if (f_ != nullptr) std::fclose(f_);
}

void InputFile::seek(std::uint64_t offset) {
  if (std::fseek(f_, static_cast<long>(offset), SEEK_SET) != 0) {
    throw core::InputError(at_byte(name_, offset), "cannot seek there");
  }
  offset_ = offset;
}

void InputFile::read(std::size_t n, std::vector<std::uint8_t>& out, std::string_view what) {
  if (n > size_ - std::min(size_, offset_)) {
    throw core::InputError(at_byte(name_, offset_),
                           fmt::format("truncated: {} needs {} bytes, the file has {} left", what,
                                       n, size_ - std::min(size_, offset_)));
  }
  // A record holds at most a chunk and its header: a longer one is a corrupt length field
  // that would otherwise be read into memory whole.
  if (n > kMaxChunkBytes + (std::size_t{1} << 20)) {
    throw core::InputError(at_byte(name_, offset_),
                           fmt::format("{} of {} bytes: more than calstand reads at once (a "
                                       "corrupt length field?)",
                                       what, n));
  }
  out.resize(n);
  const std::size_t got = n == 0 ? 0 : std::fread(out.data(), 1, n, f_);
  if (got != n) {
    throw core::InputError(at_byte(name_, offset_ + got),
                           fmt::format("truncated: {} needs {} bytes, read {}", what, n, got));
  }
  offset_ += n;
}

std::size_t InputFile::read_some(std::size_t n, std::uint8_t* out) {
  const std::size_t got = std::fread(out, 1, n, f_);
  offset_ += got;
  return got;
}

std::string Cursor::where() const {
  return where_.empty() ? fmt::format("byte {}", base_ + pos_)
                        : fmt::format("{} byte {}", where_, base_ + pos_);
}

void Cursor::fail(const std::string& why) const { throw core::InputError(where(), why); }

void Cursor::need(std::size_t n, const char* what) const {
  if (n > remaining()) {
    fail(fmt::format("truncated: a {} field needs {} bytes, the record has {} left", what, n,
                     remaining()));
  }
}

void decompress(std::string_view method, std::span<const std::uint8_t> in, std::size_t size,
                std::vector<std::uint8_t>& out, const std::string& where) {
  if (size > kMaxChunkBytes) {
    throw core::InputError(where, fmt::format("a chunk of {} bytes uncompressed: more than the "
                                              "{} calstand reads (a corrupt size field?)",
                                              size, kMaxChunkBytes));
  }
  out.resize(size);
  if (method == "zstd") {
    // One decompression context per thread, reused chunk after chunk (a fresh one per chunk
    // allocates and clears its tables each time).
    thread_local const std::unique_ptr<ZSTD_DCtx, std::size_t (*)(ZSTD_DCtx*)> context(
        ZSTD_createDCtx(), &ZSTD_freeDCtx);
    if (!context) throw core::InputError(where, "zstd: cannot create a decompression context");
    const std::size_t got =
        ZSTD_decompressDCtx(context.get(), out.data(), size, in.data(), in.size());
    if (ZSTD_isError(got) != 0) {
      throw core::InputError(where, fmt::format("zstd: {}", ZSTD_getErrorName(got)));
    }
    if (got != size) {
      throw core::InputError(
          where, fmt::format("zstd: {} bytes decompressed, the record says {}", got, size));
    }
    return;
  }
  if (method == "lz4") {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)) != 0) {
      throw core::InputError(where, "lz4: cannot create a decompression context");
    }
    std::size_t produced = 0;
    std::size_t consumed = 0;
    std::size_t status = 1;
    while (status != 0 && consumed < in.size()) {
      std::size_t dst = size - produced;
      std::size_t src = in.size() - consumed;
      status =
          LZ4F_decompress(ctx, out.data() + produced, &dst, in.data() + consumed, &src, nullptr);
      if (LZ4F_isError(status) != 0) {
        const std::string why = LZ4F_getErrorName(status);
        LZ4F_freeDecompressionContext(ctx);
        throw core::InputError(where, "lz4: " + why);
      }
      produced += dst;
      consumed += src;
      if (dst == 0 && src == 0) break;  // no progress: output full or input ends mid-frame
    }
    LZ4F_freeDecompressionContext(ctx);
    if (produced != size) {
      throw core::InputError(
          where, fmt::format("lz4: {} bytes decompressed, the record says {}", produced, size));
    }
    return;
  }
  if (method == "bz2") {
    auto dst = static_cast<unsigned int>(size);
    // bzlib's API takes non-const pointers but does not write the source.
    const int rc =
        BZ2_bzBuffToBuffDecompress(reinterpret_cast<char*>(out.data()), &dst,
                                   const_cast<char*>(reinterpret_cast<const char*>(in.data())),
                                   static_cast<unsigned int>(in.size()), 0, 0);
    if (rc != BZ_OK) throw core::InputError(where, fmt::format("bz2: error {}", rc));
    if (dst != size) {
      throw core::InputError(
          where, fmt::format("bz2: {} bytes decompressed, the record says {}", dst, size));
    }
    return;
  }
  throw core::InputError(where, fmt::format("unknown compression '{}' (none, lz4, zstd and bz2 "
                                            "are read)",
                                            method));
}

std::uint32_t crc32(std::span<const std::uint8_t> bytes) {
  // ISA-L's CRC-32 with the gzip/zlib polynomial and conventions (identical values), folded
  // with PCLMULQDQ: three times zlib 1.2.13's speed, and the CRC of every MCAP chunk's records
  // was a quarter of the reading time.
  return crc32_gzip_refl(0, bytes.data(), bytes.size());
}

// sensor_msgs/Imu after its header: orientation (4 float64), orientation_covariance (9),
// angular_velocity (3), angular_velocity_covariance (9), linear_acceleration (3),
// linear_acceleration_covariance (9) (sensor_msgs/msg/Imu.msg, common_interfaces).
constexpr std::size_t kImuDoubles = 4 + 9 + 3 + 9 + 3 + 9;
constexpr std::size_t kAngularVelocityIndex = 4 + 9;
constexpr std::size_t kLinearAccelerationIndex = 4 + 9 + 3 + 9;

void read_imu_body(const std::uint8_t* p, ImuRecord& out) {
  // Only the six doubles used (copying all 37 was a tenth of an import's time).
  double w[3];
  double f[3];
  std::memcpy(w, p + kAngularVelocityIndex * 8, sizeof w);
  std::memcpy(f, p + kLinearAccelerationIndex * 8, sizeof f);
  out.gyro_rad_s = {w[0], w[1], w[2]};
  out.accel_mps2 = {f[0], f[1], f[2]};
}

std::string decode_imu_cdr(std::span<const std::uint8_t> data, ImuRecord& out) {
  // CDR as ROS 2 writes it (OMG DDS-XTypes 1.3, 7.4.3.5 "Encapsulation": a 4-byte header,
  // 0x00 0x01 = plain CDR little-endian; DDSI-RTPS 2.3, 10 "Serialized Payload
  // Representation"), primitives aligned to their size from the end of that header.
  if (data.size() < 4) return fmt::format("{} bytes, shorter than the CDR header", data.size());
  if (data[0] != 0x00 || data[1] != 0x01) {
    return fmt::format("CDR encapsulation {:02x}{:02x} is not plain little-endian CDR (0001)",
                       data[0], data[1]);
  }
  const std::uint8_t* body = data.data() + 4;
  const std::size_t n = data.size() - 4;
  if (n < 12) return fmt::format("{} bytes, shorter than a std_msgs/Header", data.size());
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::uint32_t len = 0;
  std::memcpy(&sec, body, 4);
  std::memcpy(&nanosec, body + 4, 4);
  std::memcpy(&len, body + 8, 4);  // frame_id: length including its terminating NUL
  if (len > n - 12) return fmt::format("frame_id of {} bytes overruns the message", len);
  std::size_t pos = 12 + len;
  pos = (pos + 7) & ~std::size_t{7};
  if (pos + kImuDoubles * 8 > n) {
    return fmt::format("{} bytes, too short for sensor_msgs/msg/Imu (needs {})", data.size(),
                       4 + pos + kImuDoubles * 8);
  }
  out.t_s = stamp_seconds(sec, nanosec);
  read_imu_body(body + pos, out);
  return {};
}

std::string decode_imu_ros1(std::span<const std::uint8_t> data, ImuRecord& out) {
  // ROS 1 serialisation (ROS wiki, msg/Serialization): little-endian, no alignment; Header is
  // uint32 seq, time stamp (uint32 secs, uint32 nsecs), string frame_id (uint32 length, bytes).
  const std::size_t n = data.size();
  if (n < 16) return fmt::format("{} bytes, shorter than a std_msgs/Header", n);
  std::uint32_t secs = 0;
  std::uint32_t nsecs = 0;
  std::uint32_t len = 0;
  std::memcpy(&secs, data.data() + 4, 4);
  std::memcpy(&nsecs, data.data() + 8, 4);
  std::memcpy(&len, data.data() + 12, 4);
  if (len > n - 16) return fmt::format("frame_id of {} bytes overruns the message", len);
  const std::size_t pos = 16 + len;
  if (pos + kImuDoubles * 8 != n) {
    return fmt::format("{} bytes, not the size of a sensor_msgs/Imu with this frame_id ({})", n,
                       pos + kImuDoubles * 8);
  }
  out.t_s = stamp_seconds(secs, nsecs);
  read_imu_body(data.data() + pos, out);
  return {};
}

bool is_imu_type(std::string_view type, std::string_view encoding) {
  if (encoding == "cdr") return type == "sensor_msgs/msg/Imu";
  if (encoding == "ros1") return type == "sensor_msgs/Imu";
  return false;
}

namespace {

class MessageRecording final : public RecordingReader {
 public:
  explicit MessageRecording(std::unique_ptr<MessageSource> source) : source_(std::move(source)) {}

  std::string format() const override { return source_->format(); }

  std::vector<TopicInfo> topics() override {
    if (source_->indexed()) return source_->channels();
    // No index: count by reading every message once.
    source_->rewind(-1);
    std::vector<std::uint64_t> count;
    std::vector<std::uint64_t> first;
    std::vector<std::uint64_t> last;
    RawMessage m;
    while (source_->next(m)) {
      if (m.channel >= count.size()) {
        count.resize(m.channel + 1, 0);
        first.resize(m.channel + 1, 0);
        last.resize(m.channel + 1, 0);
      }
      if (count[m.channel]++ == 0) first[m.channel] = m.log_time_ns;
      first[m.channel] = std::min(first[m.channel], m.log_time_ns);
      last[m.channel] = std::max(last[m.channel], m.log_time_ns);
    }
    std::vector<TopicInfo> out = source_->channels();
    for (std::size_t i = 0; i < out.size(); ++i) {
      out[i].count = i < count.size() ? count[i] : 0;
      out[i].rate_hz = out[i].count > 1 && last[i] > first[i]
                           ? static_cast<double>(out[i].count - 1) /
                                 (static_cast<double>(last[i] - first[i]) * 1e-9)
                           : 0.0;
    }
    scanned_ = true;
    return out;
  }

  void select(const std::string& topic) override {
    topic_ = topic;
    channel_ = -1;
    if (source_->indexed() || scanned_) {
      const auto& ch = source_->channels();
      for (std::size_t i = 0; i < ch.size(); ++i) {
        if (ch[i].name == topic) {
          check_imu(ch[i], source_->name());
          channel_ = static_cast<int>(i);
        }
      }
      if (channel_ < 0) throw missing_topic();
    }
    source_->rewind(channel_);
  }

  bool read(std::vector<ImuRecord>& batch, std::size_t max) override {
    batch.clear();
    RawMessage m;
    while (batch.size() < max && source_->next(m)) {
      if (channel_ < 0) {
        const TopicInfo& ch = source_->channels()[m.channel];
        if (ch.name != topic_) continue;
        check_imu(ch, where(m));
        channel_ = static_cast<int>(m.channel);
      }
      if (static_cast<int>(m.channel) != channel_) continue;
      const TopicInfo& ch = source_->channels()[m.channel];
      ImuRecord r;
      const std::string why =
          ch.encoding == "cdr" ? decode_imu_cdr(m.data, r) : decode_imu_ros1(m.data, r);
      if (!why.empty()) {
        throw core::InputError(where(m), fmt::format("a message on {} ({}, {}) does not decode: {}",
                                                     ch.name, ch.type, ch.encoding, why));
      }
      if (!r.gyro_rad_s.allFinite() || !r.accel_mps2.allFinite()) {
        throw core::InputError(
            where(m), fmt::format("a message on {} has a value that is not a finite number "
                                  "(angular_velocity {} {} {}, linear_acceleration {} {} {})",
                                  ch.name, r.gyro_rad_s.x(), r.gyro_rad_s.y(), r.gyro_rad_s.z(),
                                  r.accel_mps2.x(), r.accel_mps2.y(), r.accel_mps2.z()));
      }
      batch.push_back(r);
    }
    if (batch.empty() && channel_ < 0) throw missing_topic();
    return !batch.empty();
  }

  std::optional<TopicInfo> selected() const override {
    if (channel_ < 0) return std::nullopt;
    return source_->channels()[static_cast<std::size_t>(channel_)];
  }
  std::string position() const override { return source_->position(); }
  double progress() const override { return source_->progress(); }

 private:
  std::string where(const RawMessage& m) const {
    return m.where.empty() ? source_->position() : m.where;
  }

  static void check_imu(const TopicInfo& ch, const std::string& where) {
    if (!ch.imu) {
      throw core::InputError(
          where, fmt::format("topic {} is {} ({} encoding), not an IMU topic (sensor_msgs/msg/Imu "
                             "in cdr, or sensor_msgs/Imu in ros1)",
                             ch.name, ch.type, ch.encoding));
    }
  }

  core::InputError missing_topic() const {
    std::string names;
    for (const TopicInfo& t : source_->channels()) {
      names += (names.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
    }
    return core::InputError(source_->name(),
                            fmt::format("no topic {} in the recording (topics: {})", topic_,
                                        names.empty() ? "none" : names));
  }

  std::unique_ptr<MessageSource> source_;
  std::string topic_;
  int channel_ = -1;
  bool scanned_ = false;
};

}  // namespace

std::unique_ptr<RecordingReader> make_message_recording(std::unique_ptr<MessageSource> source) {
  return std::make_unique<MessageRecording>(std::move(source));
}

}  // namespace recordings

}  // namespace calstand::store

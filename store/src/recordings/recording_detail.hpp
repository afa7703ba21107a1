#pragma once
// Private: what the recording readers share: a buffered file, little-endian decoding with
// bounds checks, decompression, the two serialisations of sensor_msgs/Imu, and the reader of
// any message-based recording (MCAP, ROS 1 bag, ROS 2 bag) on top of a MessageSource.

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "store/recording_reader.hpp"

namespace calstand::store::recordings {

/// `FILE: byte N`: where a content error is.
std::string at_byte(const std::string& file, std::uint64_t offset);

/// A file read front to back (or from an offset) through one buffer. Errors name the file.
class InputFile {
 public:
  explicit InputFile(const std::filesystem::path& path);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  const std::string& name() const { return name_; }
  std::uint64_t size() const { return size_; }
  std::uint64_t offset() const { return offset_; }
  void seek(std::uint64_t offset);
  /// Reads exactly `n` bytes into `out` (resized). Throws InputError "truncated" naming `what`
  /// and the offset when the file ends first.
  void read(std::size_t n, std::vector<std::uint8_t>& out, std::string_view what);
  /// Reads up to `n` bytes; returns how many (0 at the end of the file).
  std::size_t read_some(std::size_t n, std::uint8_t* out);

 private:
  std::string name_;
  std::FILE* f_ = nullptr;
  std::uint64_t size_ = 0;
  std::uint64_t offset_ = 0;
};

/// Little-endian fields of a byte range, with bounds checks. `base` is the range's offset in
/// the file (or in a decompressed chunk), for messages: `where_prefix byte N`. The prefix is
/// borrowed (no allocation per record): it must outlive the cursor.
class Cursor {
 public:
  Cursor(std::span<const std::uint8_t> bytes, std::string_view where_prefix, std::uint64_t base)
      : bytes_(bytes), where_(where_prefix), base_(base) {}

  std::size_t pos() const { return pos_; }
  std::size_t remaining() const { return bytes_.size() - pos_; }
  bool done() const { return pos_ >= bytes_.size(); }
  void skip(std::size_t n) { need(n, "bytes"), pos_ += n; }

  std::uint8_t u8() { return fixed<std::uint8_t>("u8"); }
  std::uint16_t u16() { return fixed<std::uint16_t>("u16"); }
  std::uint32_t u32() { return fixed<std::uint32_t>("u32"); }
  std::uint64_t u64() { return fixed<std::uint64_t>("u64"); }
  double f64() { return fixed<double>("float64"); }
  /// u32 length then that many bytes.
  std::string_view string32() {
    const std::uint32_t n = u32();
    return bytes_as_text(n);
  }
  std::span<const std::uint8_t> bytes(std::size_t n) {
    need(n, "bytes");
    const auto s = bytes_.subspan(pos_, n);
    pos_ += n;
    return s;
  }
  std::string_view bytes_as_text(std::size_t n) {
    const auto s = bytes(n);
    return {reinterpret_cast<const char*>(s.data()), s.size()};
  }
  /// Throws InputError at the current position.
  [[noreturn]] void fail(const std::string& why) const;
  std::string where() const;

 private:
  void need(std::size_t n, const char* what) const;
  template <class T>
  T fixed(const char* what) {
    need(sizeof(T), what);
    T v;
    std::memcpy(&v, bytes_.data() + pos_, sizeof(T));  // the targets are little-endian
    pos_ += sizeof(T);
    return v;
  }

  std::span<const std::uint8_t> bytes_;
  std::string_view where_;
  std::uint64_t base_ = 0;
  std::size_t pos_ = 0;
};

/// The largest chunk decompressed [bytes]: writers make chunks of a few MiB; a size field
/// beyond this is a corrupt file, refused rather than allocated.
inline constexpr std::size_t kMaxChunkBytes = std::size_t{1} << 30;

/// Decompresses `in` into `out`, which holds exactly `size` bytes afterwards. `method`:
/// "lz4" (the LZ4 frame format), "zstd", "bz2". Throws InputError at `where` on any failure,
/// including a decompressed size other than `size`.
void decompress(std::string_view method, std::span<const std::uint8_t> in, std::size_t size,
                std::vector<std::uint8_t>& out, const std::string& where);

/// CRC-32 (ISO-HDLC, zlib's) of `bytes`.
std::uint32_t crc32(std::span<const std::uint8_t> bytes);

/// Decodes sensor_msgs/msg/Imu in CDR (ROS 2, with its 4-byte encapsulation header) or
/// sensor_msgs/Imu in the ROS 1 serialisation. Returns an empty string, or why it fails.
std::string decode_imu_cdr(std::span<const std::uint8_t> data, ImuRecord& out);
std::string decode_imu_ros1(std::span<const std::uint8_t> data, ImuRecord& out);

/// Whether (type, encoding) is an IMU message the decoders above read.
bool is_imu_type(std::string_view type, std::string_view encoding);

/// A stamp as a time in seconds, the same operation for every format (and for the CSV a test
/// writes): sec + nanosec * 1e-9.
inline double stamp_seconds(std::int64_t sec, std::uint32_t nanosec) {
  return static_cast<double>(sec) + static_cast<double>(nanosec) * 1e-9;
}

/// One message of a message-based recording. `data` stays valid until the next next().
struct RawMessage {
  std::uint32_t channel = 0;  ///< index into MessageSource::channels()
  std::uint64_t log_time_ns = 0;
  std::span<const std::uint8_t> data;
  std::string where;  ///< `FILE: byte N` (or the row) for messages about it; filled lazily
};

/// The messages of a recording in file order, format by format.
class MessageSource {
 public:
  virtual ~MessageSource() = default;
  virtual std::string format() const = 0;
  /// The file or folder read, for messages about the whole recording.
  virtual std::string name() const = 0;
  /// Channels known so far (all of them once next() has returned false, or from the index).
  virtual const std::vector<TopicInfo>& channels() const = 0;
  /// True when channels() and their counts are complete without reading (an index or summary).
  virtual bool indexed() const = 0;
  /// Reads from the beginning again. `only`: the channel wanted (a source may skip the rest);
  /// negative: all.
  virtual void rewind(int only) = 0;
  virtual bool next(RawMessage& m) = 0;
  /// Where the next message is being read from (file and byte, or table row).
  virtual std::string position() const = 0;
  virtual double progress() const = 0;
};

/// A RecordingReader over a MessageSource: topics from the index or a counting pass, IMU
/// messages decoded by the channel's encoding.
std::unique_ptr<RecordingReader> make_message_recording(std::unique_ptr<MessageSource> source);

/// The format readers (one file each).
std::unique_ptr<MessageSource> open_mcap(const std::filesystem::path& file);
std::unique_ptr<MessageSource> open_ros1_bag(const std::filesystem::path& file);
std::unique_ptr<MessageSource> open_ros2_bag(const std::filesystem::path& path);
std::unique_ptr<RecordingReader> open_euroc(const std::filesystem::path& folder);

/// The MCAP magic (MCAP specification, "Magic": 0x89 M C A P 0 \r \n).
inline constexpr std::string_view kMcapMagic{"\x89MCAP0\r\n", 8};
/// The first line of a ROS 1 bag, format 2.0 (ROS wiki, Bags/Format/2.0, "Version").
inline constexpr std::string_view kRos1BagVersion = "#ROSBAG V2.0\n";
/// The first 16 bytes of a SQLite 3 database (sqlite.org/fileformat.html, "Magic Header").
inline constexpr std::string_view kSqliteMagic{"SQLite format 3\0", 16};

}  // namespace calstand::store::recordings

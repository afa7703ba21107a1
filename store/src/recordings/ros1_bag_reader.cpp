// ROS 1 bags, format 2.0, read from its specification (ROS wiki, "Bags/Format/2.0"): the
// version line, then records of a header (u32 length; fields of u32 length + "name=value") and
// data (u32 length + bytes). Chunks (op 0x05, compression none, bz2 or lz4) hold connection
// (op 0x07) and message data (op 0x02) records; the index section at the bag header's
// index_pos repeats the connections and holds one chunk info (op 0x06) per chunk with each
// connection's message count.

#include <fmt/format.h>

#include <algorithm>
#include <unordered_map>

#include "recording_detail.hpp"

namespace calstand::store::recordings {
namespace {

// Record ops (Bags/Format/2.0, "Records").
constexpr std::uint8_t kRos1MessageData = 0x02;
constexpr std::uint8_t kRos1BagHeader = 0x03;
constexpr std::uint8_t kRos1Chunk = 0x05;
constexpr std::uint8_t kRos1ChunkInfo = 0x06;
constexpr std::uint8_t kRos1Connection = 0x07;

/// The fields of a record header, by name.
struct Ros1Header {
  std::uint8_t op = 0;
  std::vector<std::pair<std::string_view, std::span<const std::uint8_t>>> fields;

  std::span<const std::uint8_t> get(std::string_view name, const Cursor& at) const {
    for (const auto& [n, v] : fields) {
      if (n == name) return v;
    }
    at.fail(fmt::format("record (op 0x{:02x}) has no field '{}'", op, name));
  }
  std::uint32_t u32(std::string_view name, const Cursor& at) const {
    const auto v = get(name, at);
    if (v.size() != 4) at.fail(fmt::format("field '{}' has {} bytes, not 4", name, v.size()));
    std::uint32_t x = 0;
    std::memcpy(&x, v.data(), 4);
    return x;
  }
  std::uint64_t u64(std::string_view name, const Cursor& at) const {
    const auto v = get(name, at);
    if (v.size() != 8) at.fail(fmt::format("field '{}' has {} bytes, not 8", name, v.size()));
    std::uint64_t x = 0;
    std::memcpy(&x, v.data(), 8);
    return x;
  }
  std::string_view text(std::string_view name, const Cursor& at) const {
    const auto v = get(name, at);
    return {reinterpret_cast<const char*>(v.data()), v.size()};
  }
};

void parse_ros1_header(std::span<const std::uint8_t> bytes, Ros1Header& h, const Cursor& at) {
  h.fields.clear();
  h.op = 0;
  Cursor c(bytes, "", 0);
  while (!c.done()) {
    const std::uint32_t len = c.u32();
    if (len > c.remaining()) at.fail("truncated: a header field overruns its header");
    const auto field = c.bytes(len);
    const auto eq = std::find(field.begin(), field.end(), std::uint8_t{'='});
    if (eq == field.end()) at.fail("a header field without '='");
    const auto n = static_cast<std::size_t>(eq - field.begin());
    const std::string_view name(reinterpret_cast<const char*>(field.data()), n);
    h.fields.emplace_back(name, field.subspan(n + 1));
    if (name == "op" && n + 2 == field.size()) h.op = field[n + 1];
  }
}

// A ROS time (u32 secs, u32 nsecs) as nanoseconds.
std::uint64_t ros1_time_ns(std::uint64_t packed) {
  return (packed & 0xffffffffULL) * 1000000000ULL + (packed >> 32);
}

class Ros1BagSource final : public MessageSource {
 public:
  explicit Ros1BagSource(const std::filesystem::path& path)
      : file_(path), prefix_(file_.name() + ":") {
    std::vector<std::uint8_t> line;
    file_.read(kRos1BagVersion.size(), line, "the version line");
    // The bag header record follows the version line.
    const std::uint64_t at = file_.offset();
    read_record(at);
    Cursor where(header_bytes_, prefix_, at);
    if (header_.op != kRos1BagHeader) where.fail("the first record is not the bag header");
    index_pos_ = header_.u64("index_pos", where);
    data_start_ = file_.offset();
    if (index_pos_ != 0) {
      if (index_pos_ > file_.size()) {
        throw core::InputError(
            at_byte(file_.name(), file_.size()),
            fmt::format("truncated: the bag header puts the index at byte {}, past the end",
                        index_pos_));
      }
      read_index();
    }
    rewind(-1);
  }

  std::string format() const override { return "ros1-bag"; }
  std::string name() const override { return file_.name(); }
  const std::vector<TopicInfo>& channels() const override { return channels_; }
  bool indexed() const override { return indexed_; }

  void rewind(int only) override {
    only_ = only;
    file_.seek(data_start_);
    in_chunk_ = false;
    record_offset_ = data_start_;
  }

  bool next(RawMessage& m) override {
    const std::uint64_t end = index_pos_ != 0 ? index_pos_ : file_.size();
    for (;;) {
      if (in_chunk_) {
        if (chunk_pos_ < chunk_.size()) {
          if (inner_record(m)) return true;
          continue;
        }
        in_chunk_ = false;
      }
      if (file_.offset() >= end) return false;
      record_offset_ = file_.offset();
      read_record(record_offset_);
      Cursor where(header_bytes_, prefix_, record_offset_);
      if (header_.op == kRos1Chunk) {
        open_chunk(where);
      } else if (header_.op == kRos1Connection) {
        connection(where, data_);
      } else if (header_.op == kRos1MessageData) {
        if (message(where, data_, m)) return true;
      }
    }
  }

  std::string position() const override {
    if (in_chunk_) {
      return fmt::format("{}: byte {} (chunk), byte {} of its records", file_.name(),
                         record_offset_, inner_offset_);
    }
    return at_byte(file_.name(), record_offset_);
  }

  double progress() const override {
    return file_.size() == 0
               ? 1.0
               : static_cast<double>(file_.offset()) / static_cast<double>(file_.size());
  }

 private:
  // Reads the record at the file's offset: header_ and data_.
  void read_record(std::uint64_t at) {
    std::vector<std::uint8_t> len;
    file_.read(4, len, "a record's header length");
    std::uint32_t n = 0;
    std::memcpy(&n, len.data(), 4);
    file_.read(n, header_bytes_, "a record header");
    file_.read(4, len, "a record's data length");
    std::uint32_t d = 0;
    std::memcpy(&d, len.data(), 4);
    file_.read(d, data_, "a record's data");
    parse_ros1_header(header_bytes_, header_, Cursor(header_bytes_, prefix_, at));
  }

  void read_index() {
    file_.seek(index_pos_);
    std::unordered_map<std::uint32_t, std::pair<std::uint64_t, std::uint64_t>> span;
    while (file_.offset() < file_.size()) {
      const std::uint64_t at = file_.offset();
      read_record(at);
      Cursor where(header_bytes_, prefix_, at);
      if (header_.op == kRos1Connection) connection(where, data_);
      if (header_.op != kRos1ChunkInfo) continue;
      const std::uint64_t start = ros1_time_ns(header_.u64("start_time", where));
      const std::uint64_t end = ros1_time_ns(header_.u64("end_time", where));
      Cursor c(data_, prefix_, at);
      while (!c.done()) {
        const std::uint32_t conn = c.u32();
        const std::uint32_t count = c.u32();
        const auto it = conn_index_.find(conn);
        if (it == conn_index_.end()) continue;
        channels_[static_cast<std::size_t>(it->second)].count += count;
        auto [s, fresh] = span.emplace(conn, std::pair{start, end});
        if (!fresh) {
          s->second.first = std::min(s->second.first, start);
          s->second.second = std::max(s->second.second, end);
        }
      }
    }
    for (const auto& [conn, se] : span) {
      TopicInfo& t = channels_[static_cast<std::size_t>(conn_index_[conn])];
      // Chunk spans, in receive time: the rate of a topic that fills its chunks' spans.
      t.rate_hz = t.count > 1 && se.second > se.first
                      ? static_cast<double>(t.count - 1) /
                            (static_cast<double>(se.second - se.first) * 1e-9)
                      : 0.0;
    }
    indexed_ = true;
  }

  void connection(const Cursor& where, std::span<const std::uint8_t> data) {
    const std::uint32_t conn = header_.u32("conn", where);
    if (conn_index_.contains(conn)) return;
    const std::string topic(header_.text("topic", where));
    // The data is a connection header: topic, type, md5sum, message_definition, ...
    Ros1Header fields;
    parse_ros1_header(data, fields, where);
    TopicInfo t;
    t.name = topic;
    t.type = std::string(fields.text("type", where));
    t.encoding = "ros1";
    t.imu = is_imu_type(t.type, t.encoding);
    conn_index_.emplace(conn, static_cast<int>(channels_.size()));
    channels_.push_back(t);
  }

  bool message(const Cursor& where, std::span<const std::uint8_t> data, RawMessage& m) {
    const std::uint32_t conn = header_.u32("conn", where);
    const auto it = conn_index_.find(conn);
    if (it == conn_index_.end()) {
      where.fail(
          fmt::format("message on connection {}, which no connection record before it "
                      "defines",
                      conn));
    }
    if (only_ >= 0 && it->second != only_) return false;
    m.channel = static_cast<std::uint32_t>(it->second);
    m.log_time_ns = ros1_time_ns(header_.u64("time", where));
    m.data = data;
    return true;
  }

  void open_chunk(const Cursor& where) {
    const std::string compression(header_.text("compression", where));
    const std::uint32_t size = header_.u32("size", where);
    const std::string at = fmt::format("{}: byte {} (chunk)", file_.name(), record_offset_);
    if (compression == "none") {
      if (size != data_.size()) {
        throw core::InputError(at, fmt::format("size {} differs from the {} bytes of an "
                                               "uncompressed chunk",
                                               size, data_.size()));
      }
      chunk_.assign(data_.begin(), data_.end());
    } else {
      decompress(compression, data_, size, chunk_, at);
    }
    chunk_prefix_ = fmt::format("{}: byte {} (chunk), records", file_.name(), record_offset_);
    chunk_pos_ = 0;
    in_chunk_ = true;
  }

  bool inner_record(RawMessage& m) {
    inner_offset_ = chunk_pos_;
    Cursor c(std::span<const std::uint8_t>(chunk_).subspan(chunk_pos_), chunk_prefix_, chunk_pos_);
    const std::uint32_t hn = c.u32();
    const auto header = c.bytes(hn);
    const std::uint32_t dn = c.u32();
    const auto data = c.bytes(dn);
    chunk_pos_ += 8 + hn + dn;
    const Cursor where(header, chunk_prefix_, inner_offset_ + 4);
    parse_ros1_header(header, header_, where);
    if (header_.op == kRos1Connection) connection(where, data);
    if (header_.op == kRos1MessageData) return message(where, data, m);
    return false;
  }

  InputFile file_;
  std::string prefix_;        // "FILE:"
  std::string chunk_prefix_;  // "FILE: byte N (chunk), records"
  std::vector<TopicInfo> channels_;
  std::unordered_map<std::uint32_t, int> conn_index_;
  bool indexed_ = false;
  std::uint64_t index_pos_ = 0;
  std::uint64_t data_start_ = 0;
  int only_ = -1;
  std::uint64_t record_offset_ = 0;
  std::vector<std::uint8_t> header_bytes_;
  std::vector<std::uint8_t> data_;
  Ros1Header header_;
  bool in_chunk_ = false;
  std::vector<std::uint8_t> chunk_;
  std::size_t chunk_pos_ = 0;
  std::size_t inner_offset_ = 0;
};

}  // namespace

std::unique_ptr<MessageSource> open_ros1_bag(const std::filesystem::path& file) {
  return std::make_unique<Ros1BagSource>(file);
}

}  // namespace calstand::store::recordings

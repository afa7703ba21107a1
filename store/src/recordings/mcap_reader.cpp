// MCAP, read from its specification (mcap.dev/spec, format version 0, "MCAP Format
// Specification"): the magic, then records (opcode u8, content length u64, content), all
// integers little-endian, strings as u32 length + UTF-8 bytes. The data section is read front
// to back, a chunk at a time (decompressed into one reused buffer, its CRC checked); the
// summary section (found through the footer) gives the channels and counts without reading the
// data.

#include <fmt/format.h>

#include <algorithm>

#include "recording_detail.hpp"

namespace calstand::store::recordings {
namespace {

// Opcodes (mcap.dev/spec, "Records").
constexpr std::uint8_t kOpHeader = 0x01;
constexpr std::uint8_t kOpFooter = 0x02;
constexpr std::uint8_t kOpSchema = 0x03;
constexpr std::uint8_t kOpChannel = 0x04;
constexpr std::uint8_t kOpMessage = 0x05;
constexpr std::uint8_t kOpChunk = 0x06;
constexpr std::uint8_t kOpStatistics = 0x0B;
constexpr std::uint8_t kOpDataEnd = 0x0F;
// Footer: opcode, length, then summary_start u64, summary_offset_start u64, summary_crc u32.
constexpr std::uint64_t kFooterContent = 8 + 8 + 4;
constexpr std::uint64_t kRecordHeader = 1 + 8;
// Message: channel_id u16, sequence u32, log_time u64, publish_time u64, then the data.
constexpr std::uint64_t kMessageFixed = 2 + 4 + 8 + 8;

class McapSource final : public MessageSource {
 public:
  explicit McapSource(const std::filesystem::path& path)
      : file_(path), prefix_(file_.name() + ":") {
    std::vector<std::uint8_t> head;
    file_.read(kMcapMagic.size(), head, "the leading magic");
    if (std::string_view(reinterpret_cast<const char*>(head.data()), head.size()) != kMcapMagic) {
      throw core::InputError(at_byte(file_.name(), 0), "not an MCAP file (no leading magic)");
    }
    read_footer();
  }

  std::string format() const override { return "mcap"; }
  std::string name() const override { return file_.name(); }
  const std::vector<TopicInfo>& channels() const override { return channels_; }
  bool indexed() const override { return has_statistics_; }

  void rewind(int only) override {
    only_ = only;
    file_.seek(kMcapMagic.size());
    in_chunk_ = false;
    ended_ = false;
    record_offset_ = file_.offset();
  }

  bool next(RawMessage& m) override {
    while (!ended_) {
      if (in_chunk_) {
        if (chunk_pos_ < chunk_records_.size()) {
          if (inner_record(m)) return true;
          continue;
        }
        in_chunk_ = false;
      }
      if (top_record(m)) return true;
    }
    return false;
  }

  std::string position() const override {
    if (in_chunk_) {
      return fmt::format("{}: byte {} (chunk), byte {} of its records", file_.name(), chunk_offset_,
                         inner_offset_);
    }
    return at_byte(file_.name(), record_offset_);
  }

  double progress() const override {
    return file_.size() == 0 || ended_
               ? 1.0
               : static_cast<double>(file_.offset()) / static_cast<double>(file_.size());
  }

 private:
  void read_footer() {
    const std::uint64_t size = file_.size();
    const std::uint64_t tail = kRecordHeader + kFooterContent + kMcapMagic.size();
    if (size < kMcapMagic.size() + tail) {
      throw core::InputError(at_byte(file_.name(), size),
                             "truncated: too short for an MCAP file (magic, footer, magic)");
    }
    std::vector<std::uint8_t> bytes;
    file_.seek(size - tail);
    file_.read(tail, bytes, "the footer");
    if (std::string_view(reinterpret_cast<const char*>(bytes.data()) + tail - kMcapMagic.size(),
                         kMcapMagic.size()) != kMcapMagic) {
      throw core::InputError(at_byte(file_.name(), size),
                             "truncated: the file does not end with the MCAP magic (a recording "
                             "cut short, or still being written)");
    }
    Cursor c(bytes, prefix_, size - tail);
    if (c.u8() != kOpFooter || c.u64() != kFooterContent) {
      throw core::InputError(at_byte(file_.name(), size - tail),
                             "no footer record before the closing magic");
    }
    const std::uint64_t summary_start = c.u64();
    if (summary_start != 0) {
      if (summary_start < kMcapMagic.size() || summary_start > size - tail) {
        throw core::InputError(at_byte(file_.name(), size - tail),
                               fmt::format("footer: summary_start {} is outside the data before "
                                           "it",
                                           summary_start));
      }
      read_summary(summary_start, size - tail);
    }
    file_.seek(kMcapMagic.size());
  }

  void read_summary(std::uint64_t start, std::uint64_t end) {
    file_.seek(start);
    std::vector<std::uint8_t> rec;
    while (file_.offset() < end) {
      const std::uint64_t at = file_.offset();
      file_.read(kRecordHeader, rec, "a summary record's opcode and length");
      Cursor h(rec, prefix_, at);
      const std::uint8_t op = h.u8();
      const std::uint64_t len = h.u64();
      if (op != kOpSchema && op != kOpChannel && op != kOpStatistics) {
        if (len > end - file_.offset()) {
          throw core::InputError(at_byte(file_.name(), at), "summary record overruns the footer");
        }
        file_.seek(file_.offset() + len);
        continue;
      }
      file_.read(len, rec, "a summary record");
      Cursor c(rec, prefix_, at + kRecordHeader);
      if (op == kOpSchema) schema(c);
      if (op == kOpChannel) channel(c);
      if (op == kOpStatistics) statistics(c);
    }
    // Counts the statistics did not name are zero; a file without statistics is counted by
    // reading it.
  }

  void schema(Cursor& c) {
    const std::uint16_t id = c.u16();
    const std::string name(c.string32());
    c.string32();  // encoding (ros2msg, ros1msg, ...): the channel's message_encoding decides
    if (schema_names_.size() <= id) schema_names_.resize(id + std::size_t{1});
    schema_names_[id] = name;
  }

  void channel(Cursor& c) {
    const std::uint16_t id = c.u16();
    const std::uint16_t schema_id = c.u16();
    const std::string topic(c.string32());
    const std::string encoding(c.string32());
    if (channel_index_[id] >= 0) return;  // seen already (summary and data repeat channels)
    TopicInfo t;
    t.name = topic;
    t.encoding = encoding;
    if (schema_id != 0) {
      if (schema_id >= schema_names_.size()) {
        c.fail(
            fmt::format("channel {} ({}) names schema {}, which no schema record before it "
                        "defines",
                        id, topic, schema_id));
      }
      t.type = schema_names_[schema_id];
    }
    t.imu = is_imu_type(t.type, t.encoding);
    channel_index_[id] = static_cast<int>(channels_.size());
    channels_.push_back(t);
  }

  void statistics(Cursor& c) {
    c.u64();  // message_count
    c.u16();  // schema_count
    c.u32();  // channel_count
    c.u32();  // attachment_count
    c.u32();  // metadata_count
    c.u32();  // chunk_count
    const std::uint64_t start = c.u64();
    const std::uint64_t end = c.u64();
    const std::uint32_t map_bytes = c.u32();
    Cursor m(c.bytes(map_bytes), "", 0);
    while (!m.done()) {
      const std::uint16_t id = m.u16();
      const std::uint64_t count = m.u64();
      if (channel_index_[id] < 0) continue;
      TopicInfo& t = channels_[static_cast<std::size_t>(channel_index_[id])];
      t.count = count;
      // Statistics hold the recording's span, not each channel's: the rate of a channel that
      // spans the whole recording.
      t.rate_hz = count > 1 && end > start
                      ? static_cast<double>(count - 1) / (static_cast<double>(end - start) * 1e-9)
                      : 0.0;
    }
    has_statistics_ = true;
  }

  // One record of the data section; true when it was a message of the wanted channel.
  bool top_record(RawMessage& m) {
    record_offset_ = file_.offset();
    if (record_offset_ >= file_.size()) {
      throw core::InputError(at_byte(file_.name(), record_offset_),
                             "truncated: the data section ends without a Data End record");
    }
    file_.read(kRecordHeader, record_, "a record's opcode and length");
    Cursor h(record_, prefix_, record_offset_);
    const std::uint8_t op = h.u8();
    const std::uint64_t len = h.u64();
    if (op == kOpDataEnd || op == kOpFooter) {
      ended_ = true;
      return false;
    }
    if (op != kOpChunk && op != kOpSchema && op != kOpChannel && op != kOpMessage) {
      if (len > file_.size() - file_.offset()) {
        throw core::InputError(at_byte(file_.name(), record_offset_),
                               fmt::format("truncated: record (opcode 0x{:02x}) of {} bytes, the "
                                           "file has {} left",
                                           op, len, file_.size() - file_.offset()));
      }
      file_.seek(file_.offset() + len);
      return false;
    }
    file_.read(len, record_, fmt::format("a record (opcode 0x{:02x})", op));
    Cursor c(record_, prefix_, record_offset_ + kRecordHeader);
    if (op == kOpChunk) {
      open_chunk(c);
      return false;
    }
    if (op == kOpSchema) schema(c);
    if (op == kOpChannel) channel(c);
    if (op == kOpMessage) return message(c, m);
    return false;
  }

  void open_chunk(Cursor& c) {
    chunk_offset_ = record_offset_;
    c.u64();  // message_start_time
    c.u64();  // message_end_time
    const std::uint64_t size = c.u64();
    const std::uint32_t crc = c.u32();
    const std::string compression(c.string32());
    const std::uint64_t records_len = c.u64();
    const auto records = c.bytes(records_len);
    const std::string where = fmt::format("{}: byte {} (chunk)", file_.name(), chunk_offset_);
    if (compression.empty()) {
      if (size != records_len) {
        throw core::InputError(where, fmt::format("uncompressed_size {} differs from the {} bytes "
                                                  "of records of an uncompressed chunk",
                                                  size, records_len));
      }
      chunk_view_ = records;
    } else {
      decompress(compression, records, size, chunk_buffer_, where);
      chunk_view_ = chunk_buffer_;
    }
    // A CRC of 0 means none was computed (mcap.dev/spec, "Chunk").
    if (crc != 0) {
      const std::uint32_t actual = crc32(chunk_view_);
      if (actual != crc) {
        throw core::InputError(where, fmt::format("CRC mismatch: the records' CRC-32 is {:08x}, "
                                                  "the chunk says {:08x} (corrupt data)",
                                                  actual, crc));
      }
    }
    chunk_records_ = chunk_view_;
    chunk_prefix_ = fmt::format("{}: byte {} (chunk), records", file_.name(), chunk_offset_);
    chunk_pos_ = 0;
    in_chunk_ = true;
  }

  bool inner_record(RawMessage& m) {
    inner_offset_ = chunk_pos_;
    Cursor h(chunk_records_.subspan(chunk_pos_), chunk_prefix_, chunk_pos_);
    if (h.remaining() < kRecordHeader) {
      h.fail("truncated: a record header in the chunk's records");
    }
    const std::uint8_t op = h.u8();
    const std::uint64_t len = h.u64();
    if (len > h.remaining()) {
      throw core::InputError(position(), fmt::format("truncated: record (opcode 0x{:02x}) of {} "
                                                     "bytes, the chunk has {} left",
                                                     op, len, h.remaining()));
    }
    Cursor c(chunk_records_.subspan(chunk_pos_ + kRecordHeader, len), chunk_prefix_,
             chunk_pos_ + kRecordHeader);
    chunk_pos_ += kRecordHeader + len;
    if (op == kOpMessage) return message(c, m);
    if (op == kOpSchema) schema(c);
    if (op == kOpChannel) channel(c);
    return false;
  }

  bool message(Cursor& c, RawMessage& m) {
    if (c.remaining() < kMessageFixed) c.fail("truncated: a message record");
    const std::uint16_t id = c.u16();
    c.u32();  // sequence
    const std::uint64_t log_time = c.u64();
    c.u64();  // publish_time
    const int index = channel_index_[id];
    if (index < 0) {
      c.fail(fmt::format("message on channel {}, which no channel record before it defines", id));
    }
    if (only_ >= 0 && index != only_) return false;
    m.channel = static_cast<std::uint32_t>(index);
    m.log_time_ns = log_time;
    m.data = c.bytes(c.remaining());
    return true;
  }

  InputFile file_;
  std::string prefix_;        // "FILE:"
  std::string chunk_prefix_;  // "FILE: byte N (chunk), records"
  std::vector<TopicInfo> channels_;
  std::vector<int> channel_index_ = std::vector<int>(65536, -1);
  std::vector<std::string> schema_names_;
  bool has_statistics_ = false;
  int only_ = -1;
  bool ended_ = false;
  std::uint64_t record_offset_ = 0;
  std::vector<std::uint8_t> record_;
  bool in_chunk_ = false;
  std::uint64_t chunk_offset_ = 0;
  std::size_t inner_offset_ = 0;
  std::vector<std::uint8_t> chunk_buffer_;
  std::span<const std::uint8_t> chunk_view_;
  std::span<const std::uint8_t> chunk_records_;
  std::size_t chunk_pos_ = 0;
};

}  // namespace

std::unique_ptr<MessageSource> open_mcap(const std::filesystem::path& file) {
  return std::make_unique<McapSource>(file);
}

}  // namespace calstand::store::recordings

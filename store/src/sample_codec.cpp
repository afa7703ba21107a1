#include "store/sample_codec.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "store/error.hpp"

namespace calstand::store {

// The layout is little-endian; copying host values byte for byte is only right on such hosts
// (every platform calstand targets).
static_assert(std::endian::native == std::endian::little, "sample chunks assume little-endian");

namespace {

constexpr char kMagic[4] = {'C', 'S', 'M', 'P'};

template <class T>
void put(std::uint8_t*& p, T v) {
  std::memcpy(p, &v, sizeof v);
  p += sizeof v;
}

template <class T>
T get(const std::uint8_t*& p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  p += sizeof v;
  return v;
}

[[noreturn]] void bad_chunk(const std::string& why) {
  throw StoreError("decode sample chunk", why);
}

}  // namespace

std::size_t sample_bytes(SampleEncoding encoding) {
  return encoding == SampleEncoding::kCompact ? kCompactSampleBytes : kExactSampleBytes;
}

ChunkEncoder::ChunkEncoder(SampleEncoding encoding, ChunkLimits limits)
    : encoding_(encoding), limits_(limits) {
  if (limits_.max_samples == 0) throw std::invalid_argument("ChunkLimits.max_samples is 0");
  bytes_.resize(kChunkHeaderBytes + sample_bytes(encoding_) * limits_.max_samples);
}

void ChunkEncoder::clear() {
  size_ = kChunkHeaderBytes;
  count_ = 0;
}

bool ChunkEncoder::fits(const core::ImuSample& s) const {
  if (count_ == 0) return true;
  if (count_ >= limits_.max_samples) return false;
  if (encoding_ == SampleEncoding::kExact) return true;
  const double span = limits_.max_span_s;
  // Written so that NaN offsets fail the test and start a new chunk.
  return std::abs(s.receive_time_s - first_receive_s_) <= span &&
         std::abs(s.device_time_s - first_device_s_) <= span &&
         s.sequence - first_sequence_ <= 0xFFFFu;
}

void ChunkEncoder::append(const core::ImuSample& s) {
  if (!fits(s)) throw std::logic_error("ChunkEncoder::append: sample does not fit the chunk");
  if (count_ == 0) {
    first_receive_s_ = s.receive_time_s;
    first_device_s_ = s.device_time_s;
    first_sequence_ = s.sequence;
  }
  std::uint8_t* p = bytes_.data() + size_;
  if (encoding_ == SampleEncoding::kCompact) {
    put(p, static_cast<float>(s.receive_time_s - first_receive_s_));
    put(p, static_cast<float>(s.device_time_s - first_device_s_));
    put(p, static_cast<std::uint16_t>(s.sequence - first_sequence_));
    for (int i = 0; i < 3; ++i) put(p, static_cast<float>(s.gyro_dps[i]));
    for (int i = 0; i < 3; ++i) put(p, static_cast<float>(s.accel_mps2[i]));
    put(p, static_cast<float>(s.temperature_c));
  } else {
    put(p, s.receive_time_s);
    put(p, s.device_time_s);
    put(p, s.sequence);
    for (int i = 0; i < 3; ++i) put(p, s.gyro_dps[i]);
    for (int i = 0; i < 3; ++i) put(p, s.accel_mps2[i]);
    put(p, s.temperature_c);
  }
  size_ = static_cast<std::size_t>(p - bytes_.data());
  ++count_;
  last_receive_s_ = s.receive_time_s;
}

std::span<const std::uint8_t> ChunkEncoder::bytes() const {
  std::uint8_t* h = bytes_.data();
  std::memcpy(h, kMagic, 4);
  h += 4;
  put(h, kChunkLayoutVersion);
  put(h, static_cast<std::uint8_t>(encoding_));
  put(h, std::uint16_t{0});
  put(h, count_);
  put(h, first_sequence_);
  put(h, count_ == 0 ? 0.0 : first_receive_s_);
  put(h, count_ == 0 ? 0.0 : first_device_s_);
  return {bytes_.data(), size_};
}

ChunkHeader read_chunk_header(std::span<const std::uint8_t> blob) {
  if (blob.size() < kChunkHeaderBytes) {
    bad_chunk("blob of " + std::to_string(blob.size()) + " bytes is shorter than the header");
  }
  if (std::memcmp(blob.data(), kMagic, 4) != 0) bad_chunk("wrong magic (expected CSMP)");
  const std::uint8_t* p = blob.data() + 4;
  const auto version = get<std::uint8_t>(p);
  if (version != kChunkLayoutVersion) {
    bad_chunk("layout version " + std::to_string(version) + " is not 1");
  }
  const auto encoding = get<std::uint8_t>(p);
  if (encoding != 1 && encoding != 2) bad_chunk("unknown encoding " + std::to_string(encoding));
  get<std::uint16_t>(p);
  ChunkHeader h;
  h.encoding = static_cast<SampleEncoding>(encoding);
  h.count = get<std::uint32_t>(p);
  h.first_sequence = get<std::uint32_t>(p);
  h.first_receive_time_s = get<double>(p);
  h.first_device_time_s = get<double>(p);
  const std::size_t expected = kChunkHeaderBytes + sample_bytes(h.encoding) * h.count;
  if (blob.size() != expected) {
    bad_chunk(std::to_string(blob.size()) + " bytes, expected " + std::to_string(expected) +
              " for " + std::to_string(h.count) + " samples");
  }
  return h;
}

void decode_chunk(std::span<const std::uint8_t> blob, std::vector<core::ImuSample>& out) {
  const ChunkHeader h = read_chunk_header(blob);
  out.reserve(out.size() + h.count);
  const std::uint8_t* p = blob.data() + kChunkHeaderBytes;
  for (std::uint32_t n = 0; n < h.count; ++n) {
    core::ImuSample s;
    if (h.encoding == SampleEncoding::kCompact) {
      s.receive_time_s = h.first_receive_time_s + get<float>(p);
      s.device_time_s = h.first_device_time_s + get<float>(p);
      s.sequence = h.first_sequence + get<std::uint16_t>(p);
      for (int i = 0; i < 3; ++i) s.gyro_dps[i] = get<float>(p);
      for (int i = 0; i < 3; ++i) s.accel_mps2[i] = get<float>(p);
      s.temperature_c = get<float>(p);
    } else {
      s.receive_time_s = get<double>(p);
      s.device_time_s = get<double>(p);
      s.sequence = get<std::uint32_t>(p);
      for (int i = 0; i < 3; ++i) s.gyro_dps[i] = get<double>(p);
      for (int i = 0; i < 3; ++i) s.accel_mps2[i] = get<double>(p);
      s.temperature_c = get<double>(p);
    }
    out.push_back(s);
  }
}

std::vector<core::ImuSample> decode_chunk(std::span<const std::uint8_t> blob) {
  std::vector<core::ImuSample> out;
  decode_chunk(blob, out);
  return out;
}

std::vector<std::uint8_t> encode_chunk(std::span<const core::ImuSample> samples,
                                       SampleEncoding encoding, ChunkLimits limits) {
  if (samples.empty()) throw std::invalid_argument("encode_chunk: no samples");
  ChunkEncoder enc(encoding, limits);
  for (const auto& s : samples) {
    if (!enc.fits(s)) throw std::invalid_argument("encode_chunk: samples do not fit one chunk");
    enc.append(s);
  }
  const auto b = enc.bytes();
  return {b.begin(), b.end()};
}

}  // namespace calstand::store

// The Epson UART codec: register commands and replies, the burst frame and its checksum, raw
// counts to units, and the format's options (docs/protocols.md, "Epson M-G3xx/G5xx").
#include "drivers/epson_protocol.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace calstand::drivers::epson {
namespace {

void epson_put_be16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v >> 8));
  out.push_back(static_cast<std::uint8_t>(v & 0xFFu));
}

std::uint16_t epson_be16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

void epson_put_value(std::vector<std::uint8_t>& out, std::int32_t v, int width_bits) {
  const auto u = static_cast<std::uint32_t>(v);
  if (width_bits == 32) epson_put_be16(out, static_cast<std::uint16_t>(u >> 16));
  epson_put_be16(out, static_cast<std::uint16_t>(u & 0xFFFFu));
}

std::int32_t epson_value(const std::uint8_t* p, int width_bits) {
  if (width_bits == 32) {
    const std::uint32_t u = (std::uint32_t{epson_be16(p)} << 16) | epson_be16(p + 2);
    return static_cast<std::int32_t>(u);
  }
  return static_cast<std::int16_t>(epson_be16(p));
}

// 32-bit output is the 16-bit value with 16 more bits of fraction ([G362] 7.8, 7.9).
double epson_lsb_scale(int width_bits) { return width_bits == 32 ? 1.0 / 65536.0 : 1.0; }

std::int32_t epson_saturate(double counts, int width_bits) {
  const double hi = width_bits == 32 ? double{std::numeric_limits<std::int32_t>::max()} : 32767.0;
  const double lo = width_bits == 32 ? double{std::numeric_limits<std::int32_t>::min()} : -32768.0;
  const double r = std::round(counts);
  if (!(r < hi)) return static_cast<std::int32_t>(hi);
  if (!(r > lo)) return static_cast<std::int32_t>(lo);
  return static_cast<std::int32_t>(r);
}

}  // namespace

std::vector<std::uint8_t> read_command(std::uint8_t address) {
  return {static_cast<std::uint8_t>(address & 0x7Fu), 0x00, kDelimiter};
}

std::vector<std::uint8_t> write_command(std::uint8_t address, std::uint8_t data) {
  return {static_cast<std::uint8_t>(address | kWriteBit), data, kDelimiter};
}

std::optional<std::uint16_t> find_read_reply(std::span<const std::uint8_t> received,
                                             std::uint8_t address) {
  if (received.size() < 4) return std::nullopt;
  const std::uint8_t* p = received.data() + received.size() - 4;
  if (p[0] != (address & 0x7Fu) || p[3] != kDelimiter) return std::nullopt;
  return epson_be16(p + 1);
}

std::size_t burst_size(int width_bits) {
  const std::size_t value_bytes = width_bits == 32 ? 4 : 2;
  return 1 + 2 + 7 * value_bytes + 2 + 2 + 1;
}

std::uint16_t burst_checksum(std::span<const std::uint8_t> words) {
  std::uint32_t sum = 0;
  for (std::size_t i = 0; i + 1 < words.size(); i += 2) sum += epson_be16(words.data() + i);
  return static_cast<std::uint16_t>(sum & 0xFFFFu);
}

std::vector<std::uint8_t> encode_burst(const BurstFields& f, int width_bits) {
  std::vector<std::uint8_t> out;
  out.reserve(burst_size(width_bits));
  out.push_back(kBurstHeader);
  epson_put_be16(out, f.flags);
  epson_put_value(out, f.temperature, width_bits);
  for (std::int32_t g : f.gyro) epson_put_value(out, g, width_bits);
  for (std::int32_t a : f.accel) epson_put_value(out, a, width_bits);
  epson_put_be16(out, f.count);
  epson_put_be16(out, burst_checksum(std::span(out).subspan(1)));
  out.push_back(kDelimiter);
  return out;
}

std::optional<BurstFields> parse_burst(std::span<const std::uint8_t> frame, int width_bits) {
  const std::size_t size = burst_size(width_bits);
  if (frame.size() != size || frame[0] != kBurstHeader || frame[size - 1] != kDelimiter) {
    return std::nullopt;
  }
  if (burst_checksum(frame.subspan(1, size - 4)) != epson_be16(frame.data() + size - 3)) {
    return std::nullopt;
  }
  const std::size_t step = width_bits == 32 ? 4 : 2;
  const std::uint8_t* p = frame.data() + 1;
  BurstFields f;
  f.flags = epson_be16(p);
  p += 2;
  f.temperature = epson_value(p, width_bits);
  p += step;
  for (auto& g : f.gyro) {
    g = epson_value(p, width_bits);
    p += step;
  }
  for (auto& a : f.accel) {
    a = epson_value(p, width_bits);
    p += step;
  }
  f.count = epson_be16(p);
  return f;
}

double gyro_dps(const ModelScale& m, std::int32_t raw, int width_bits) {
  return raw * m.gyro_dps_per_lsb * epson_lsb_scale(width_bits);
}

double accel_mps2(const ModelScale& m, std::int32_t raw, int width_bits) {
  return raw * m.accel_mg_per_lsb * epson_lsb_scale(width_bits) * 1e-3 * kStandardGravity;
}

double temperature_c(const ModelScale& m, std::int32_t raw, int width_bits) {
  return m.temp_c_per_lsb * (raw * epson_lsb_scale(width_bits) - m.temp_lsb_at_25c) + 25.0;
}

std::int32_t gyro_raw(const ModelScale& m, double dps, int width_bits) {
  return epson_saturate(dps / m.gyro_dps_per_lsb / epson_lsb_scale(width_bits), width_bits);
}

std::int32_t accel_raw(const ModelScale& m, double mps2, int width_bits) {
  return epson_saturate(
      mps2 / kStandardGravity * 1e3 / m.accel_mg_per_lsb / epson_lsb_scale(width_bits), width_bits);
}

std::int32_t temperature_raw(const ModelScale& m, double celsius, int width_bits) {
  return epson_saturate(
      ((celsius - 25.0) / m.temp_c_per_lsb + m.temp_lsb_at_25c) / epson_lsb_scale(width_bits),
      width_bits);
}

Options Options::from_settings(const WireFormatSettings& settings, bool require_rate) {
  const auto& j = settings.options;
  const std::string& where = settings.where;
  Options o;
  o.rate = find_output_rate(settings.sample_rate_hz);
  if (o.rate == nullptr && require_rate) {
    // The schema cannot know the device's rates: DOUT_RATE makes only these.
    throw core::InputError(where + ".sample_rate_hz",
                           fmt::format("{:g} Hz is not an Epson DOUT_RATE rate ({})",
                                       settings.sample_rate_hz, output_rate_names()));
  }
  if (!j.is_object()) throw core::InputError(where, "must be an object");
  if (j.contains("model")) {
    if (!j["model"].is_string() || find_model(j["model"].get<std::string>()) == nullptr) {
      throw core::InputError(where + ".model", fmt::format("unknown model {} (known: {})",
                                                           j["model"].dump(), model_names()));
    }
    o.model = j["model"].get<std::string>();
  }
  if (j.contains("width_bits")) {
    if (!j["width_bits"].is_number_integer() ||
        (j["width_bits"].get<int>() != 16 && j["width_bits"].get<int>() != 32)) {
      throw core::InputError(where + ".width_bits", "must be 16 or 32");
    }
    o.width_bits = j["width_bits"].get<int>();
  }
  o.filter_code = moving_average_code(o.rate != nullptr ? o.rate->recommended_taps : 0);
  if (j.contains("filter") && !(j["filter"].is_string() && j["filter"] == "recommended")) {
    const auto code =
        j["filter"].is_string() ? epson::filter_code(j["filter"].get<std::string>()) : std::nullopt;
    if (!code) {
      throw core::InputError(where + ".filter",
                             fmt::format("unknown filter {}: \"recommended\", "
                                         "\"moving_average_N\" (N 0, 2, 4 ... 128) or "
                                         "\"kaiser_N_fcF\" (N 32, 64, 128; F 50, 100, 200, 400)",
                                         j["filter"].dump()));
    }
    o.filter_code = *code;
  }
  if (j.contains("count_step")) {
    if (j["count_step"] == "base") {
      o.count_step = CountStep::kBase;
    } else if (j["count_step"] == "output") {
      o.count_step = CountStep::kOutput;
    } else {
      throw core::InputError(where + ".count_step", "must be \"base\" or \"output\"");
    }
  }
  return o;
}

}  // namespace calstand::drivers::epson

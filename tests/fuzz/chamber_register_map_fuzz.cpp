// libFuzzer target: chamber register map decoding. Byte 0 picks the float32 word order, the
// next 8 bytes are four register words; the rest is JSON text for a generic map.
//   - Every field of every built-in map (watlow-f4, watlow-f4t in both word orders) decodes the
//     words: int16/uint16 to a finite value that encodes back to the same words, float32 to
//     the same bits unless NaN or infinite (which encode_value refuses); too few words decode
//     to NaN.
//   - The JSON text, when it parses, goes to register_map_from_json, which must either return
//     a map that validates or throw core::InputError, never crash or throw anything else; a map
//     it returns decodes the words under the same rules.
// Any broken invariant aborts.
#include <array>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <span>
#include <string_view>

#include "core/error.hpp"
#include "drivers/chamber_register_map.hpp"

namespace {

using namespace calstand::drivers;

void check(bool ok) {
  if (!ok) std::abort();
}

void check_field(const RegisterField& field, std::span<const std::uint16_t, 4> words) {
  const int n = field.register_count();
  check(n == 1 || n == 2);
  const std::span<const std::uint16_t> used = words.first(static_cast<std::size_t>(n));
  const double v = decode_value(field, used);
  check(std::isnan(decode_value(field, used.first(used.size() - 1))));
  const auto back = encode_value(field, v);
  if (field.encoding == RegisterEncoding::kFloat32) {
    if (!std::isfinite(v)) {
      check(!back);
      return;
    }
  } else {
    // A positive finite scale times a count: finite unless the scale is near DBL_MAX, and
    // exact enough to round back unless the product is subnormal.
    if (!std::isfinite(v)) {
      check(!back);
      return;
    }
    if (v != 0.0 && std::abs(v) < DBL_MIN) return;
  }
  check(back.has_value() && back->count == n);
  for (int i = 0; i < n; ++i) check(back->words[std::size_t(i)] == used[std::size_t(i)]);
}

void check_map(const ChamberRegisterMap& map, std::span<const std::uint16_t, 4> words) {
  map.validate("fuzz");  // a map that was built must validate (throws, so aborts, if not)
  check_field(map.process_value, words);
  check_field(map.setpoint, words);
  if (map.ramp_rate) check_field(*map.ramp_rate, words);
  if (map.mode) check(map.mode->control != map.mode->standby);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 9) return 0;
  const WordOrder order = data[0] & 1 ? WordOrder::kLowFirst : WordOrder::kHighFirst;
  std::array<std::uint16_t, 4> words{};
  for (std::size_t i = 0; i < 4; ++i) {
    words[i] = static_cast<std::uint16_t>(data[1 + 2 * i] << 8 | data[2 + 2 * i]);
  }
  const std::span<const std::uint16_t, 4> w(words);

  try {
    check_map(watlow_f4_map(), w);
    check_map(watlow_f4t_map(WordOrder::kHighFirst), w);
    check_map(watlow_f4t_map(WordOrder::kLowFirst), w);
  } catch (...) {
    std::abort();  // the built-in maps are valid
  }

  const std::string_view text(reinterpret_cast<const char*>(data + 9), size - 9);
  const auto doc = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded()) return 0;
  ChamberRegisterMap map;
  try {
    map = register_map_from_json(doc, "chamber.connection.map", order);
  } catch (const calstand::core::InputError& e) {
    check(std::strlen(e.what()) > 0);
    return 0;
  } catch (...) {
    std::abort();
  }
  try {
    check_map(map, w);
  } catch (...) {
    std::abort();
  }
  return 0;
}

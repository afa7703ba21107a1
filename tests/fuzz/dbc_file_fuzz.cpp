// libFuzzer target: arbitrary text into the DBC parser (drivers/dbc_file.hpp). It must either
// parse or refuse with core::InputError naming "FILE:LINE"; never crash, hang or throw anything
// else. What it accepts must hold the parser's promises: messages of at most 8 bytes, ids
// within 11 bits (29 with CAN_EFF_FLAG), every signal 1..64 bits inside the message's bytes,
// float signals 32 or 64 bits, at most one multiplexer switch per message; and decoding any
// payload through any signal's CanField must not crash.
//
// Kept seeds (tests/fuzz/seeds/dbc_file_fuzz): the two shipped examples, every construct, and
// broken lines (cut strings, CAN FD, extended multiplexing, bad numbers).
#include <linux/can.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/error.hpp"
#include "drivers/dbc_file.hpp"

namespace {

void dbc_fuzz_check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace calstand::drivers;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  DbcFile f;
  try {
    f = DbcFile::parse(text, "fuzz.dbc");
  } catch (const calstand::core::InputError& e) {
    dbc_fuzz_check(std::string_view(e.what()).starts_with("fuzz.dbc:"));
    return 0;
  }
  std::array<std::uint8_t, 8> payload{};
  for (std::size_t i = 0; i < payload.size(); ++i)
    payload[i] = static_cast<std::uint8_t>(size * 31 + i * 17);
  const std::span<const std::uint8_t, 8> p(payload);
  for (const auto& m : f.messages) {
    dbc_fuzz_check(m.dlc <= 8);
    if (m.id & CAN_EFF_FLAG) {
      dbc_fuzz_check((m.id & ~(CAN_EFF_FLAG | CAN_EFF_MASK)) == 0);
    } else {
      dbc_fuzz_check(m.id <= CAN_SFF_MASK);
    }
    int switches = 0;
    for (const auto& s : m.signals) {
      dbc_fuzz_check(s.length_bits >= 1 && s.length_bits <= 64);
      const CanField field = s.field();
      dbc_fuzz_check(field.bytes_needed() <= m.dlc);
      if (field.type == FieldType::kFloat) {
        dbc_fuzz_check(field.length_bits == 32 || field.length_bits == 64);
      }
      switches += s.mux == DbcSignal::Mux::kSwitch ? 1 : 0;
      (void)field.decode(p);
    }
    dbc_fuzz_check(switches <= 1);
  }
  return 0;
}

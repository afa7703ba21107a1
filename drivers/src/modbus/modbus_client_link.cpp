#include "drivers/modbus_client_link.hpp"

#include <fmt/format.h>
#include <modbus/modbus.h>

#include <cerrno>

namespace calstand::drivers {
namespace {

LinkStatus::Kind classify(int err) {
  if (err == ETIMEDOUT) return LinkStatus::Kind::kTimeout;
  if (err > MODBUS_ENOBASE && err <= EMBXGTAR) return LinkStatus::Kind::kException;
  if (err >= EMBBADCRC && err <= EMBBADSLAVE) return LinkStatus::Kind::kBadResponse;
  return LinkStatus::Kind::kLinkDown;
}

char parity_letter(Parity p) {
  switch (p) {
    case Parity::kNone:
      return 'N';
    case Parity::kEven:
      return 'E';
    case Parity::kOdd:
      return 'O';
  }
  return 'N';
}

}  // namespace

ModbusClientLink::ModbusClientLink(const ModbusChamberOptions& options)
    : options_(options), name_(options.link_name()) {}

ModbusClientLink::~ModbusClientLink() {
  close();
  if (ctx_ != nullptr) modbus_free(ctx_);
}

LinkStatus ModbusClientLink::failure(const char* what) {
  const int err = errno;
  const auto kind = classify(err);
  // After garbage or a late reply the next read would start mid-frame (or pick up the previous
  // transaction's answer): drop whatever is still buffered.
  if (kind == LinkStatus::Kind::kBadResponse || kind == LinkStatus::Kind::kTimeout) {
    if (ctx_ != nullptr && open_) modbus_flush(ctx_);
  }
  return {kind, fmt::format("{}: {}: {}", name_, what, modbus_strerror(err))};
}

LinkStatus ModbusClientLink::connect() {
  close();
  if (ctx_ == nullptr) {
    if (options_.transport == ModbusTransport::kTcp) {
      ctx_ = modbus_new_tcp(options_.host.c_str(), options_.port);
    } else {
      ctx_ = modbus_new_rtu(options_.serial.path.c_str(), options_.serial.baud_rate,
                            parity_letter(options_.serial.parity), 8, 1);
    }
    if (ctx_ == nullptr) {
      return {LinkStatus::Kind::kLinkDown, fmt::format("{}: cannot create a libmodbus context: {}",
                                                       name_, modbus_strerror(errno))};
    }
    const auto timeout_us = static_cast<std::uint32_t>(options_.timeout_ms) * 1000u;
    modbus_set_response_timeout(ctx_, timeout_us / 1000000u, timeout_us % 1000000u);
    // The gap allowed inside one response: a frame cut short must not hold the poll longer than
    // a missing one would.
    modbus_set_byte_timeout(ctx_, timeout_us / 1000000u, timeout_us % 1000000u);
    modbus_set_error_recovery(ctx_, MODBUS_ERROR_RECOVERY_NONE);
  }
  if (modbus_set_slave(ctx_, options_.unit_id) != 0) return failure("set unit id");
  if (modbus_connect(ctx_) != 0) {
    auto s = failure("connect");
    s.kind = LinkStatus::Kind::kLinkDown;
    return s;
  }
  open_ = true;
  return {};
}

void ModbusClientLink::close() noexcept {
  if (ctx_ != nullptr && open_) modbus_close(ctx_);
  open_ = false;
}

LinkStatus ModbusClientLink::read_registers(RegisterKind kind, std::uint16_t address,
                                            std::span<std::uint16_t> out) {
  if (!open_) return {LinkStatus::Kind::kLinkDown, name_ + ": not connected"};
  const int n = static_cast<int>(out.size());
  const int rc = kind == RegisterKind::kHolding
                     ? modbus_read_registers(ctx_, address, n, out.data())
                     : modbus_read_input_registers(ctx_, address, n, out.data());
  if (rc != n) {
    if (rc >= 0) {
      return {LinkStatus::Kind::kBadResponse,
              fmt::format("{}: read {} registers at {}: got {}", name_, n, address, rc)};
    }
    return failure(fmt::format("read register {}", address).c_str());
  }
  return {};
}

LinkStatus ModbusClientLink::write_registers(std::uint16_t address,
                                             std::span<const std::uint16_t> words) {
  if (!open_) return {LinkStatus::Kind::kLinkDown, name_ + ": not connected"};
  const int n = static_cast<int>(words.size());
  const int rc = n == 1 ? modbus_write_register(ctx_, address, words[0])
                        : modbus_write_registers(ctx_, address, n, words.data());
  if (rc < 0) return failure(fmt::format("write register {}", address).c_str());
  return {};
}

LinkStatus ModbusClientLink::read_field(const RegisterField& field, double& value,
                                        RegisterWords& raw) {
  raw.count = field.register_count();
  auto s = read_registers(field.kind, field.address,
                          std::span<std::uint16_t>(raw.words.data(), std::size_t(raw.count)));
  if (s.ok()) value = decode_value(field, raw.span());
  return s;
}

LinkStatus ModbusClientLink::write_field(const RegisterField& field, double value) {
  const auto words = encode_value(field, value);
  if (!words) {
    return {LinkStatus::Kind::kException,
            fmt::format("{}: {} cannot be encoded as {} (scale {}) at register {}", name_, value,
                        to_string(field.encoding), field.scale, field.address)};
  }
  return write_registers(field.address, words->span());
}

}  // namespace calstand::drivers

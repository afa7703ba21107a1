#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "drivers/chamber_register_map.hpp"
#include "drivers/modbus_chamber_options.hpp"

typedef struct _modbus modbus_t;  // NOLINT: libmodbus' own opaque type, kept out of our headers

namespace calstand::drivers {

/// Outcome of one Modbus request, classified so that the driver can decide what follows.
struct LinkStatus {
  enum class Kind {
    kOk,
    kTimeout,      ///< no (complete) response within the response timeout
    kBadResponse,  ///< garbage: bad CRC, wrong length, wrong unit or transaction id
    kException,    ///< the controller answered with a Modbus exception (it refused)
    kLinkDown,     ///< the connection is gone (reset, refused, closed) or was never opened
  };
  Kind kind = Kind::kOk;
  std::string message;  ///< "<link>: <what>: <why>"; empty when ok

  bool ok() const { return kind == Kind::kOk; }
};

/// A Modbus client (master) connection to one controller over libmodbus TCP or RTU, reading and
/// writing register-map fields. RAII: closes on destruction. Not thread safe (one owner at a
/// time; ModbusChamber serialises it with a mutex). The constructor does no I/O.
class ModbusClientLink {
 public:
  explicit ModbusClientLink(const ModbusChamberOptions& options);
  ~ModbusClientLink();
  ModbusClientLink(const ModbusClientLink&) = delete;
  ModbusClientLink& operator=(const ModbusClientLink&) = delete;

  /// Opens the connection (TCP connect within the response timeout, or the serial port).
  LinkStatus connect();
  void close() noexcept;
  bool is_open() const { return open_; }

  /// Reads `count` registers of `kind` from `address` into `out`.
  LinkStatus read_registers(RegisterKind kind, std::uint16_t address, std::span<std::uint16_t> out);
  /// Writes holding registers from `address` (function 0x06 for one, 0x10 for more, so a
  /// float32 changes in one request and the controller never sees half of it).
  LinkStatus write_registers(std::uint16_t address, std::span<const std::uint16_t> words);

  /// Reads a field and decodes it; `raw` receives the words (for sensor-fault sentinels).
  LinkStatus read_field(const RegisterField& field, double& value, RegisterWords& raw);
  /// Encodes and writes a field; kException without I/O when the value cannot be encoded.
  LinkStatus write_field(const RegisterField& field, double value);

  const std::string& name() const { return name_; }

 private:
  LinkStatus failure(const char* what);

  ModbusChamberOptions options_;
  std::string name_;
  modbus_t* ctx_ = nullptr;
  bool open_ = false;
};

}  // namespace calstand::drivers

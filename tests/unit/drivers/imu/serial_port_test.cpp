#include "drivers/serial_port.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "drivers/imu_frame.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::uint8_t>;

/// A pseudo-terminal pair: the test writes on the master as a device would; the code under
/// test opens the slave path as it would open /dev/ttyUSB0.
class PtyPair {
 public:
  PtyPair() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0) {
      throw std::runtime_error("cannot create a pseudo-terminal");
    }
    // Non-blocking so that read() below can give up instead of hanging the test.
    ::fcntl(master_, F_SETFL, ::fcntl(master_, F_GETFL) | O_NONBLOCK);
    slave_path_ = ::ptsname(master_);
  }
  ~PtyPair() {
    if (master_ >= 0) ::close(master_);
  }
  PtyPair(const PtyPair&) = delete;
  PtyPair& operator=(const PtyPair&) = delete;

  const std::string& slave_path() const { return slave_path_; }
  void write(const Bytes& bytes) const {
    ASSERT_EQ(::write(master_, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }
  /// What the slave side wrote, waiting up to ~1 s for `count` bytes.
  Bytes read(std::size_t count) const {
    Bytes out;
    for (int tries = 0; tries < 100 && out.size() < count; ++tries) {
      std::uint8_t buf[256];
      const ssize_t n = ::read(master_, buf, sizeof buf);
      if (n > 0) {
        out.insert(out.end(), buf, buf + n);
      } else {
        ::usleep(10'000);
      }
    }
    return out;
  }
  void close_master() {
    ::close(master_);
    master_ = -1;
  }

 private:
  int master_ = -1;
  std::string slave_path_;
};

/// Reads from `port` until `count` bytes arrived or 2 s passed.
Bytes read_n(SerialPort& port, std::size_t count) {
  Bytes out;
  const auto deadline = std::chrono::steady_clock::now() + 2s;
  while (out.size() < count && std::chrono::steady_clock::now() < deadline) {
    std::uint8_t buf[128];
    const IoResult r = port.read(buf, 100ms);
    EXPECT_TRUE(r.ok()) << r.error;
    if (!r.ok()) break;
    out.insert(out.end(), buf, buf + r.bytes);
  }
  return out;
}

TEST(SerialOptions, RejectsUnsupportedBaudNamingTheField) {
  SerialOptions o{"/dev/ttyUSB0", 12345, Parity::kNone};
  try {
    o.validate();
    FAIL() << "expected InputError";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "serial.baud_rate");
    EXPECT_NE(std::string(e.what()).find("12345"), std::string::npos);
  }
  SerialPort port(o);
  EXPECT_THROW(port.open(), core::InputError);
  EXPECT_THROW((SerialOptions{"", 115200, Parity::kNone}.validate()), core::InputError);
}

TEST(SerialPort, BadPathErrorNamesThePathAndTheOsError) {
  SerialPort port({"/dev/calstand-no-such-tty", 115200, Parity::kNone});
  try {
    port.open();
    FAIL() << "expected runtime_error";
  } catch (const core::InputError&) {
    FAIL() << "an OS failure is not a config error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/dev/calstand-no-such-tty"), std::string::npos) << what;
    EXPECT_NE(what.find("No such file or directory"), std::string::npos) << what;
  }
  EXPECT_FALSE(port.is_open());
}

TEST(SerialPort, NotATerminalIsAnErrorNamingThePath) {
  SerialPort port({"/dev/null", 9600, Parity::kNone});
  try {
    port.open();
    FAIL() << "expected runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/null"), std::string::npos) << e.what();
  }
}

TEST(SerialPort, ReadWithoutOpenIsAnErrorNotAThrow) {
  SerialPort port({"/dev/ttyS99", 115200, Parity::kNone});
  std::uint8_t buf[4];
  const IoResult r = port.read(buf, 1ms);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error.find("/dev/ttyS99"), std::string::npos);
}

TEST(SerialPort, ReadTimesOutWithoutData) {
  PtyPair pty;
  SerialPort port({pty.slave_path(), 115200, Parity::kNone});
  port.open();
  std::uint8_t buf[16];
  const auto t0 = std::chrono::steady_clock::now();
  const IoResult r = port.read(buf, 50ms);
  const auto waited = std::chrono::steady_clock::now() - t0;
  EXPECT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.bytes, 0u);
  EXPECT_GE(waited, 45ms);
  EXPECT_LT(waited, 1s);
}

TEST(SerialPort, RawModePassesEveryByteValueUnchanged) {
  // In cooked mode the line discipline would eat or translate 0x03 (^C), 0x0D (CR), 0x11/0x13
  // (XON/XOFF), 0x7F (DEL) and others; a binary IMU stream needs every value intact.
  PtyPair pty;
  SerialPort port({pty.slave_path(), 921600, Parity::kNone});
  port.open();
  Bytes all(256);
  for (int i = 0; i < 256; ++i) all[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(i);
  pty.write(all);
  EXPECT_EQ(read_n(port, all.size()), all);
}

TEST(SerialPort, DecodesImuFramesWrittenByTheDevice) {
  for (Parity parity : {Parity::kNone, Parity::kEven, Parity::kOdd}) {
    SCOPED_TRACE(static_cast<int>(parity));
    PtyPair pty;
    SerialPort port({pty.slave_path(), 115200, parity});
    port.open();

    Bytes stream{0x00, 0xFF, 0xA5};  // line noise before the device's first frame
    for (std::uint32_t seq = 0; seq < 20; ++seq) {
      core::ImuSample s;
      s.sequence = seq;
      s.device_time_s = 0.01 * seq;
      s.gyro_dps = {1.0, 2.0, 3.0};
      s.accel_mps2 = {0.0, 0.0, 9.8125};
      s.temperature_c = 30.0;
      const Bytes f = encode_imu_frame(s);
      stream.insert(stream.end(), f.begin(), f.end());
    }
    pty.write(stream);

    CalstandFrameDecoder decoder;
    std::vector<core::ImuSample> out;
    const Bytes got = read_n(port, stream.size());
    decoder.feed(got, out);
    ASSERT_EQ(out.size(), 20u);
    for (std::uint32_t seq = 0; seq < 20; ++seq) EXPECT_EQ(out[seq].sequence, seq);
    EXPECT_EQ(out[19].accel_mps2.z(), 9.8125);
    EXPECT_EQ(decoder.stats().garbage_bytes, 3u);
    EXPECT_EQ(decoder.stats().crc_errors, 0u);
  }
}

TEST(SerialPort, WritesReachTheDevice) {
  PtyPair pty;
  SerialPort port({pty.slave_path(), 115200, Parity::kNone});
  port.open();
  const Bytes cmd{':', 'r', 'e', 'a', 'd', '\r', '\n', 0x00, 0x11};
  const IoResult r = port.write(cmd, 500ms);
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.bytes, cmd.size());
  EXPECT_EQ(pty.read(cmd.size()), cmd);  // no CR/LF translation on output either
}

TEST(SerialPort, DeviceGoneIsAnErrorNotAHang) {
  PtyPair pty;
  SerialPort port({pty.slave_path(), 115200, Parity::kNone});
  port.open();
  pty.close_master();
  std::uint8_t buf[16];
  const IoResult r = port.read(buf, 500ms);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error.find(pty.slave_path()), std::string::npos) << r.error;
}

}  // namespace
}  // namespace calstand::drivers

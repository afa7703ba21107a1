// The protocol simulator seen through a plain libmodbus client: registers, encodings, refusals,
// unit ids, garbage, stop/start.

#include "drivers/modbus_chamber_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>

#include "modbus_test_support.hpp"

namespace calstand::drivers {
namespace {

using namespace test;

/// A libmodbus client context, freed on destruction.
struct Client {
  modbus_t* ctx;
  explicit Client(modbus_t* c, int unit_id = 1) : ctx(c) {
    modbus_set_slave(ctx, unit_id);
    modbus_set_response_timeout(ctx, 0, 200000);
  }
  ~Client() {
    modbus_close(ctx);
    modbus_free(ctx);
  }
  bool connect() { return modbus_connect(ctx) == 0; }
  /// Registers read, or an empty vector (errno set) on failure.
  std::vector<std::uint16_t> read(int address, int count) {
    std::vector<std::uint16_t> out(static_cast<std::size_t>(count));
    if (modbus_read_registers(ctx, address, count, out.data()) != count) return {};
    return out;
  }
  /// 0 when written, otherwise errno (e.g. EMBXILVAL for a refused value).
  int write(int address, std::vector<std::uint16_t> words) {
    const int rc = words.size() == 1
                       ? modbus_write_register(ctx, address, words[0])
                       : modbus_write_registers(ctx, address, int(words.size()), words.data());
    return rc < 0 ? errno : 0;
  }
};

std::vector<std::uint16_t> float_words(double value) {
  const auto w = encode_value(watlow_f4t_map().setpoint, value);
  return {w->words[0], w->words[1]};
}

double as_float(const std::vector<std::uint16_t>& words) {
  return decode_value(watlow_f4t_map().setpoint, words);
}

class ModbusChamberServerTest : public ::testing::Test {
 protected:
  core::StationConfig station = quick_chamber_station();
  std::mutex mutex;
  sim::SimWorld world{station};
  SimChamberBackend backend{world, mutex};

  core::ChamberState chamber() {
    std::lock_guard lock(mutex);
    return world.chamber_state();
  }
};

TEST_F(ModbusChamberServerTest, TcpServesTheF4tRegistersAndActsOnWrites) {
  auto server = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
  server->start();
  ASSERT_GT(server->port(), 0);
  Client c(modbus_new_tcp("127.0.0.1", server->port()));
  ASSERT_TRUE(c.connect());
  EXPECT_NEAR(as_float(c.read(2820, 2)), chamber().air_temperature_c, 1e-3);
  EXPECT_NEAR(as_float(c.read(2782, 2)), station.chamber.ambient_c, 1e-3);
  EXPECT_EQ(c.read(2730, 1), std::vector<std::uint16_t>{62});

  // A setpoint written in standby is held, not acted on, as the controller does.
  EXPECT_EQ(c.write(2782, float_words(40.0)), 0);
  EXPECT_EQ(chamber().mode, core::ChamberMode::kStandby);
  EXPECT_NEAR(as_float(c.read(2782, 2)), 40.0, 1e-4);
  EXPECT_EQ(c.write(2730, {10}), 0);
  EXPECT_EQ(chamber().mode, core::ChamberMode::kActive);
  EXPECT_NEAR(chamber().setpoint_c, 40.0, 1e-4);
  EXPECT_EQ(c.read(2730, 1), std::vector<std::uint16_t>{10});

  EXPECT_EQ(c.write(2782, float_words(500.0)), EMBXILVAL) << "beyond the chamber's range";
  EXPECT_NEAR(chamber().setpoint_c, 40.0, 1e-4);
  EXPECT_EQ(c.write(2730, {54}), EMBXILVAL) << "manual mode is not simulated";
  EXPECT_EQ(c.write(2820, float_words(20.0)), EMBXILADD) << "the process value is read-only";
  EXPECT_EQ(c.write(2782, {0x4220}), 0) << "half a float in one write is accepted";
  EXPECT_TRUE(c.read(0, 1).empty());
  EXPECT_EQ(errno, EMBXILADD);
  std::uint16_t out[2];
  const std::uint16_t in[2] = {0, 0};
  EXPECT_EQ(modbus_write_and_read_registers(c.ctx, 2782, 2, in, 2820, 2, out), -1);
  EXPECT_EQ(errno, EMBXILFUN);

  EXPECT_EQ(c.write(2730, {62}), 0);
  EXPECT_EQ(chamber().mode, core::ChamberMode::kStandby);
  EXPECT_GE(server->requests(), 10u);
}

TEST_F(ModbusChamberServerTest, RtuServesTheF4RegistersToItsUnitOnly) {
  auto server = ModbusChamberServer::rtu(watlow_f4_map(), backend, 5);
  server->start();
  Client c(modbus_new_rtu(server->slave_path().c_str(), 9600, 'N', 8, 1), 5);
  ASSERT_TRUE(c.connect()) << modbus_strerror(errno);
  const auto pv = c.read(100, 1);
  ASSERT_EQ(pv.size(), 1u) << modbus_strerror(errno);
  EXPECT_NEAR(static_cast<std::int16_t>(pv[0]) * 0.1, chamber().air_temperature_c, 0.051);
  // The F4 has no mode register: a setpoint write starts control.
  EXPECT_EQ(c.write(300, {static_cast<std::uint16_t>(-255)}), 0);  // -25.5 degC
  EXPECT_EQ(chamber().mode, core::ChamberMode::kActive);
  EXPECT_NEAR(chamber().setpoint_c, -25.5, 1e-9);
  EXPECT_EQ(c.read(300, 1), std::vector<std::uint16_t>{static_cast<std::uint16_t>(-255)});

  // Last: after another unit's request libmodbus takes the next frame on the line for that
  // unit's reply (as on a multi-drop bus), and here no other unit answers.
  Client other(modbus_new_rtu(server->slave_path().c_str(), 9600, 'N', 8, 1), 6);
  ASSERT_TRUE(other.connect());
  EXPECT_TRUE(other.read(100, 1).empty());
  EXPECT_EQ(errno, ETIMEDOUT) << "another unit's request is not answered";
}

TEST_F(ModbusChamberServerTest, GarbageDoesNotStopTheServer) {
  auto tcp = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
  tcp->start();
  for (const std::string& junk :
       {std::string("\x00\x01\x00\x00\x00\x06\x01\x03\x0b", 9),  // a frame cut short
        std::string("GET / HTTP/1.0\r\n\r\n"),                   // not Modbus at all
        std::string("\x00\x01\x00\x00\xff\xff\x01\x03\x0b\x04\x00\x02", 12)}) {  // bad length
    const int s = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(tcp->port()));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::connect(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    EXPECT_EQ(::send(s, junk.data(), junk.size(), MSG_NOSIGNAL), ssize_t(junk.size()));
    ::close(s);
  }
  Client c(modbus_new_tcp("127.0.0.1", tcp->port()));
  ASSERT_TRUE(c.connect());
  EXPECT_EQ(c.read(2730, 1).size(), 1u) << modbus_strerror(errno);

  auto rtu = ModbusChamberServer::rtu(watlow_f4_map(), backend);
  rtu->start();
  const int fd = ::open(rtu->slave_path().c_str(), O_RDWR | O_NOCTTY);
  ASSERT_GE(fd, 0);
  const std::uint8_t junk[] = {0x01, 0x03, 0x00, 0x64, 0x00, 0x01, 0xde, 0xad,  // bad CRC
                               0xff, 0x00, 0x13, 0x37};
  EXPECT_EQ(::write(fd, junk, sizeof junk), ssize_t(sizeof junk));
  ::close(fd);
  std::this_thread::sleep_for(300ms);  // past the server's byte timeout: the torn frame is dropped
  Client r(modbus_new_rtu(rtu->slave_path().c_str(), 9600, 'N', 8, 1));
  ASSERT_TRUE(r.connect());
  EXPECT_EQ(r.read(100, 1).size(), 1u) << modbus_strerror(errno);
}

TEST_F(ModbusChamberServerTest, StopDropsClientsAndStartServesTheSamePortAgain) {
  auto server = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
  server->start();
  const int port = server->port();
  Client c(modbus_new_tcp("127.0.0.1", port));
  ASSERT_TRUE(c.connect());
  ASSERT_EQ(c.read(2730, 1).size(), 1u);
  server->stop();
  EXPECT_FALSE(server->running());
  EXPECT_TRUE(c.read(2730, 1).empty()) << "the connection is gone";
  server->start();
  EXPECT_EQ(server->port(), port);
  Client again(modbus_new_tcp("127.0.0.1", port));
  ASSERT_TRUE(again.connect());
  EXPECT_EQ(again.read(2730, 1).size(), 1u);
}

}  // namespace
}  // namespace calstand::drivers

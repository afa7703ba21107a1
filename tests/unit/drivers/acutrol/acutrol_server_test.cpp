#include "drivers/acutrol_server.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <mutex>
#include <random>
#include <string>

#include "acutrol_test_support.hpp"
#include "drivers/tcp_client.hpp"
#include "sim/sim_world.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;
using test::eventually;
using test::RunningWorld;

/// A raw line client: sends one line, returns the reply line ("" on timeout or error).
class LineClient {
 public:
  explicit LineClient(std::uint16_t port) : tcp_(options(port)) {}
  std::string ask(const std::string& line, std::chrono::milliseconds timeout = 1000ms) {
    const std::string wire = line + "\n";
    if (!tcp_.write(std::span<const std::uint8_t>(
                        reinterpret_cast<const std::uint8_t*>(wire.data()), wire.size()),
                    timeout)
             .ok()) {
      return "";
    }
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (auto l = lines_.next()) return l->text;
      std::uint8_t buf[512];
      const IoResult r = tcp_.read(buf, 20ms);
      if (!r.ok()) return "";
      lines_.push(std::span<const std::uint8_t>(buf, r.bytes));
    }
    return "";
  }

 private:
  static TcpOptions options(std::uint16_t port) {
    TcpOptions o;
    o.port = port;
    return o;
  }
  TcpClient tcp_;
  acutrol::LineAssembler lines_;
};

double number(const std::string& reply) { return *acutrol::parse_number(reply).value; }

class AcutrolServerTest : public ::testing::Test {
 protected:
  void SetUp() override { server_.start(); }
  RunningWorld world_{50.0};
  SimTableBackend backend_{world_.world(), world_.mutex()};
  AcutrolServer server_{backend_};
};

TEST_F(AcutrolServerTest, ServesAnEphemeralPortAndAnswersEveryLineOnce) {
  ASSERT_NE(server_.port(), 0);
  LineClient c(server_.port());
  EXPECT_EQ(c.ask("*idn?"), "CALSTAND,ACUTROL-SIM,0,1.0");
  EXPECT_EQ(c.ask(":read:status? 1").rfind("REST,", 0), 0u);  // settled once 0.5 s at rest
  EXPECT_EQ(c.ask(":interlock? 2"), "CLOSED");
  EXPECT_EQ(c.ask(":read:pos? 3").rfind("ERR 102 ", 0), 0u);
  EXPECT_EQ(c.ask("hello").rfind("ERR 100 ", 0), 0u);
  EXPECT_EQ(c.ask(std::string(1000, 'x')).rfind("ERR 103 ", 0), 0u);
  // Still in step after the errors: the next reply is this command's.
  EXPECT_EQ(c.ask(":read:rate? 2"), "0.000000");
  EXPECT_EQ(server_.commands_served(), 7u);
}

TEST_F(AcutrolServerTest, PositionAndRateDemandsMoveTheSimulatedAxes) {
  LineClient c(server_.port());
  // A demand for a mode not selected is refused: the mode comes first.
  EXPECT_EQ(c.ask(":demand:position 2,90.0").rfind("ERR 200 ", 0), 0u);
  EXPECT_EQ(c.ask(":mode:position 2"), "OK");
  EXPECT_EQ(c.ask(":demand:position 2,90.0"), "OK");
  EXPECT_EQ(c.ask(":mode:rate 1"), "OK");
  EXPECT_EQ(c.ask(":demand:rate 1,10.0"), "OK");
  EXPECT_TRUE(eventually([&] {
    return c.ask(":read:status? 2") == "POSITION,1,CLOSED" &&
           c.ask(":read:status? 1") == "RATE,1,CLOSED";
  }));
  EXPECT_NEAR(number(c.ask(":read:pos? 2")), 90.0, 1e-3);
  EXPECT_NEAR(number(c.ask(":read:rate? 1")), 10.0, 1e-3);
  EXPECT_EQ(c.ask(":stop 1"), "OK");
  EXPECT_TRUE(eventually([&] { return c.ask(":read:status? 1") == "REST,1,CLOSED"; }));
  EXPECT_NEAR(number(c.ask(":read:rate? 1")), 0.0, 1e-3);
}

TEST_F(AcutrolServerTest, LimitsAreEnforcedAndCannotExceedTheAxis) {
  LineClient c(server_.port());
  EXPECT_EQ(c.ask(":limit 1,R,100,50"), "OK");
  EXPECT_EQ(backend_.limits(1), std::make_pair(100.0, 50.0));
  EXPECT_EQ(c.ask(":mode:rate 1"), "OK");
  const std::string refused = c.ask(":demand:rate 1,-150");
  EXPECT_EQ(refused.rfind("ERR 201 ", 0), 0u) << refused;
  EXPECT_NE(refused.find("exceeds the limit 100"), std::string::npos) << refused;
  EXPECT_EQ(c.ask(":demand:rate 1,-100"), "OK");
  // The simulated outer axis can do 400 deg/s: a software limit beyond that is refused.
  EXPECT_EQ(c.ask(":limit 1,R,1000,50").rfind("ERR 201 ", 0), 0u);
  EXPECT_EQ(backend_.limits(1), std::make_pair(100.0, 50.0));
}

TEST_F(AcutrolServerTest, OpenInterlockFaultsTheAxisAndRefusesMotionUntilClosed) {
  LineClient c(server_.port());
  backend_.open_interlock(1, "door open");
  EXPECT_EQ(c.ask(":interlock? 1"), "OPEN,door open");
  EXPECT_EQ(c.ask(":read:status? 1"), "FAULT,0,OPEN,interlock open: door open");
  EXPECT_EQ(c.ask(":mode:rate 1").rfind("ERR 300 ", 0), 0u);
  EXPECT_EQ(c.ask(":stop 1"), "OK");  // stopping is never refused
  const std::string early = c.ask(":interlock:close 1");
  EXPECT_EQ(early.rfind("ERR 301 ", 0), 0u) << early;
  EXPECT_NE(early.find("door open"), std::string::npos);
  // The other axis is not affected.
  EXPECT_EQ(c.ask(":mode:rate 2"), "OK");

  backend_.clear_interlock_cause(1);
  EXPECT_EQ(c.ask(":interlock:close 1"), "OK");
  EXPECT_EQ(c.ask(":interlock? 1"), "CLOSED");
  EXPECT_EQ(c.ask(":mode:rate 1"), "OK");
  EXPECT_EQ(c.ask(":demand:rate 1,5"), "OK");
}

TEST_F(AcutrolServerTest, ServesSeveralClientsAndSurvivesDroppedOnes) {
  LineClient a(server_.port());
  LineClient b(server_.port());
  EXPECT_EQ(a.ask(":read:rate? 1"), "0.000000");
  EXPECT_EQ(b.ask(":read:rate? 2"), "0.000000");
  EXPECT_TRUE(eventually([&] { return server_.client_count() == 2; }));
  server_.drop_clients();
  EXPECT_TRUE(eventually([&] { return server_.client_count() == 0; }));
  // TcpClient reconnects on the next call after seeing the hang-up.
  EXPECT_TRUE(eventually([&] { return a.ask("*idn?", 200ms) == "CALSTAND,ACUTROL-SIM,0,1.0"; }));
}

TEST_F(AcutrolServerTest, MutedServerReadsButNeverAnswers) {
  LineClient c(server_.port());
  server_.set_answering(false);
  const auto served = server_.commands_served();
  EXPECT_EQ(c.ask(":read:pos? 1", 150ms), "");
  EXPECT_TRUE(eventually([&] { return server_.commands_served() > served; }));
  server_.set_answering(true);
  EXPECT_EQ(c.ask(":read:rate? 1"), "0.000000");
}

TEST_F(AcutrolServerTest, StopsCleanlyWithClientsConnected) {
  LineClient c(server_.port());
  EXPECT_EQ(c.ask(":read:rate? 1"), "0.000000");
  const auto t0 = std::chrono::steady_clock::now();
  server_.stop();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);
  EXPECT_EQ(c.ask(":read:rate? 1", 200ms), "");
}

TEST_F(AcutrolServerTest, RandomLinesEachGetOneBoundedReply) {
  // Valid commands mixed with garbage, fixed seed: the controller answers every line with one
  // line, and never with anything a client could take for two.
  std::mt19937 rng(7);
  const std::vector<std::string> words{":mode:rate",
                                       ":mode:position",
                                       ":demand:rate",
                                       ":demand:position",
                                       ":read:pos?",
                                       ":read:status?",
                                       ":interlock?",
                                       ":interlock:close",
                                       ":limit",
                                       ":stop",
                                       "*idn?",
                                       "1",
                                       "2",
                                       "3",
                                       ",",
                                       "R",
                                       "-10",
                                       "1e9",
                                       "nan",
                                       " "};
  std::size_t errors = 0;
  for (int i = 0; i < 2000; ++i) {
    std::string line;
    const int n = std::uniform_int_distribution<int>(0, 6)(rng);
    for (int k = 0; k < n; ++k) {
      line += words[std::uniform_int_distribution<std::size_t>(0, words.size() - 1)(rng)];
      if (std::uniform_int_distribution<int>(0, 3)(rng) == 0) {
        line.push_back(static_cast<char>(std::uniform_int_distribution<int>(1, 255)(rng)));
      }
    }
    const std::string reply = handle_command_line(line, backend_);
    ASSERT_FALSE(reply.empty()) << line;
    ASSERT_EQ(reply.find_first_of("\r\n"), std::string::npos) << line;
    ASSERT_LE(reply.size(), acutrol::kMaxLineBytes) << line;
    if (reply.rfind("ERR ", 0) == 0) ++errors;
  }
  EXPECT_GT(errors, 1000u);
  // A burst of raw garbage over the socket: the session stays in step with its client.
  LineClient c(server_.port());
  std::string blob;
  for (int i = 0; i < 3000; ++i) {
    const char b = static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
    if (b != '\n') blob.push_back(b);
  }
  EXPECT_EQ(c.ask(blob).rfind("ERR 103 ", 0), 0u);
  EXPECT_EQ(c.ask("*idn?"), "CALSTAND,ACUTROL-SIM,0,1.0");
}

TEST(AcutrolServer, ServesOverAPseudoTerminal) {
  RunningWorld world;
  SimTableBackend backend(world.world(), world.mutex());
  AcutrolServer server(backend);
  const std::string path = server.start_serial();
  SerialOptions o;
  o.path = path;
  SerialPort port(o);
  port.open();
  const std::string wire = "*idn?\r\n";
  ASSERT_TRUE(port.write(std::span<const std::uint8_t>(
                             reinterpret_cast<const std::uint8_t*>(wire.data()), wire.size()),
                         500ms)
                  .ok());
  acutrol::LineAssembler lines;
  std::optional<acutrol::LineAssembler::Line> reply;
  for (int i = 0; i < 50 && !reply; ++i) {
    std::uint8_t buf[128];
    const IoResult r = port.read(buf, 20ms);
    ASSERT_TRUE(r.ok()) << r.error;
    lines.push(std::span<const std::uint8_t>(buf, r.bytes));
    reply = lines.next();
  }
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->text, "CALSTAND,ACUTROL-SIM,0,1.0");
}

// sim-station's world advances in slices on its runner's thread, which a busy machine keeps
// waiting (tens of ms of wall time, a second of world time at 20x). A query is answered from
// the axis at the query's time and a command acts then, as on a controller: the world is
// brought there first. Answered from where the world stood, a rate step's telemetry read its
// axis a second behind its time stamp, and the engine took the slope for a rate of 45 deg/s.
TEST(SimTableBackend, AWorldBehindItsClockIsBroughtToTheQueryFirst) {
  sim::SimWorld world(test::table_only_station());
  sim::SimWorld reference(test::table_only_station());  // the same commands, advanced on time
  std::mutex mutex;
  SimTableBackend backend(world, mutex);
  double now_s = 2.0;
  backend.set_clock([&] { return now_s; });
  // The command comes at 2 s, when the runner has not moved the world on from 0.
  ASSERT_FALSE(backend.select_mode(acutrol::kInnerAxis, acutrol::WireMode::kRate));
  ASSERT_FALSE(backend.demand_rate(acutrol::kInnerAxis, 60.0));
  EXPECT_DOUBLE_EQ(world.now_s(), 2.0);
  reference.advance_to(2.0);
  ASSERT_TRUE(reference.table().inner().command_rate(60.0).ok);
  now_s = 12.0;  // and again nothing moved it since
  const auto r = backend.report(acutrol::kInnerAxis);
  reference.advance_to(12.0);
  const core::AxisState expected = reference.table().inner().state();
  EXPECT_NEAR(r.angle_deg, expected.angle_deg, 1e-9);
  EXPECT_NEAR(r.rate_dps, 60.0, 1e-9);
}

TEST_F(AcutrolServerTest, SineDemandOscillatesAboutThePresentAngleWithinTheLimits) {
  LineClient c(server_.port());
  EXPECT_EQ(c.ask(":mode:position 2"), "OK");
  EXPECT_EQ(c.ask(":demand:position 2,45.0"), "OK");
  EXPECT_TRUE(eventually([&] { return c.ask(":read:status? 2") == "POSITION,1,CLOSED"; }));
  // The mode comes first, as for the other demands.
  EXPECT_EQ(c.ask(":demand:sine 2,1.0,2.0").rfind("ERR 200 ", 0), 0u);
  EXPECT_EQ(c.ask(":mode:sine 2"), "OK");
  // 5 deg at 2 Hz peaks at 790 deg/s^2, beyond the inner axis's 500.
  const std::string refused = c.ask(":demand:sine 2,5,2");
  EXPECT_EQ(refused.rfind("ERR 201 ", 0), 0u) << refused;
  EXPECT_EQ(c.ask(":demand:sine 2,1.0,2.0"), "OK");
  double lo = 1e9, hi = -1e9, fastest = 0.0;
  EXPECT_TRUE(eventually([&] {
    lo = std::min(lo, number(c.ask(":read:pos? 2")));
    hi = std::max(hi, number(c.ask(":read:pos? 2")));
    fastest = std::max(fastest, std::abs(number(c.ask(":read:rate? 2"))));
    return hi - lo > 1.6;  // the servo lag takes some off the 2 deg peak to peak
  })) << lo
      << " .. " << hi << " " << c.ask(":read:status? 2");
  EXPECT_GT(lo, 45.0 - 1.05);
  EXPECT_LT(hi, 45.0 + 1.05);
  EXPECT_LT(fastest, 2.0 * M_PI * 2.0 * 1.0 * 1.05);
  EXPECT_EQ(c.ask(":read:status? 2").rfind("SINE,", 0), 0u);
  EXPECT_EQ(c.ask(":stop 2"), "OK");
  EXPECT_TRUE(eventually([&] { return c.ask(":read:status? 2") == "REST,1,CLOSED"; }));
}

}  // namespace
}  // namespace calstand::drivers

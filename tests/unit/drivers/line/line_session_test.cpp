// LineSession against an independent implementation of the language its set describes: the
// acutrol-style set against the table protocol simulator (AcutrolServer), which was written
// from docs/protocols.md without command sets.
#include "drivers/line_session.hpp"

#include <gtest/gtest.h>

#include "../acutrol/acutrol_test_support.hpp"
#include "drivers/acutrol_server.hpp"

namespace calstand::drivers::line {
namespace {

using namespace std::chrono_literals;
using test::RunningWorld;

class LineSessionTest : public ::testing::Test {
 protected:
  void SetUp() override { server_.start(); }
  std::unique_ptr<LineSession> session(std::chrono::milliseconds timeout = 500ms) {
    TcpOptions o;
    o.port = server_.port();
    return std::make_unique<LineSession>(*builtin_command_set("acutrol-style"),
                                         std::make_unique<TcpClient>(o), "tcp test", timeout,
                                         "table controller", clock_, counters_, events_);
  }
  static Arguments axis(const char* a) {
    Arguments args;
    args.texts["axis"] = a;
    return args;
  }
  RunningWorld world_{50.0};
  SimTableBackend backend_{world_.world(), world_.mutex()};
  AcutrolServer server_{backend_};
  core::VirtualClock clock_;
  FaultCounters counters_;
  EventQueue events_;
};

TEST_F(LineSessionTest, RunsOperationsOfSeveralStepsAndReadsTheirFields) {
  auto s = session();
  const Outcome id = s->run("identify");
  ASSERT_TRUE(id.ok()) << id.message;
  EXPECT_EQ(id.text("identity"), "CALSTAND,ACUTROL-SIM,0,1.0");
  Arguments rate = axis("2");
  rate.numbers["rate_dps"] = 20.0;
  const Outcome r = s->run("rate", rate);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_TRUE(test::eventually([&] {
    const Outcome read = s->run("read_rate", axis("2"));
    return read.ok() && std::abs(read.number("rate_dps") - 20.0) < 0.01;
  }));
  const Outcome status = s->run("read_status", axis("2"));
  ASSERT_TRUE(status.ok()) << status.message;
  EXPECT_EQ(status.text("mode"), "rate");
  EXPECT_EQ(status.truth("fault"), false);
  ASSERT_TRUE(s->run("stop", axis("2")).ok());
}

TEST_F(LineSessionTest, ARefusalCarriesTheControllersWordsAndKeepsTheLink) {
  auto s = session();
  Arguments rate = axis("1");
  rate.numbers["rate_dps"] = 1e6;
  const Outcome r = s->run("rate", rate);
  EXPECT_EQ(r.kind, Outcome::Kind::kRefused);
  EXPECT_NE(r.message.find("ERR 201"), std::string::npos) << r.message;
  EXPECT_FALSE(r.link_lost());
  EXPECT_EQ(counters_.get("refused_commands"), 1u);
  EXPECT_TRUE(s->run("read_position", axis("1")).ok());
  const Outcome missing = s->run("read_alarms");
  EXPECT_EQ(missing.kind, Outcome::Kind::kRefused);
  EXPECT_NE(missing.message.find("has no read_alarms"), std::string::npos);
}

TEST_F(LineSessionTest, AHungControllerTimesOutAndADroppedLinkReconnects) {
  auto s = session(200ms);
  ASSERT_TRUE(s->run("read_position", axis("1")).ok());
  server_.set_answering(false);
  const Outcome hung = s->run("read_position", axis("1"));
  EXPECT_EQ(hung.kind, Outcome::Kind::kTimeout);
  EXPECT_TRUE(hung.link_lost());
  EXPECT_NE(hung.message.find("no reply from the table controller"), std::string::npos);
  server_.set_answering(true);
  ASSERT_TRUE(s->run("read_position", axis("1")).ok());
  server_.drop_clients();
  // The first command after the drop may see the hang-up; the link comes back by itself.
  EXPECT_TRUE(test::eventually([&] { return s->run("read_position", axis("1")).ok(); }));
  EXPECT_FALSE(s->link_down());
  bool lost = false, back = false;
  for (const auto& e : events_.take()) {
    lost |= e.message.find("table controller link lost") != std::string::npos;
    back |= e.message.find("table controller link back") != std::string::npos;
  }
  EXPECT_TRUE(lost);
  EXPECT_TRUE(back);
  EXPECT_GE(counters_.get("timeouts"), 1u);
}

}  // namespace
}  // namespace calstand::drivers::line

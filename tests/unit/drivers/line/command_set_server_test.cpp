// The simulator's side of a command set: the acutrol-style set served from the simulated table
// must answer as the table protocol simulator (written by hand from docs/protocols.md) does, and
// a chamber set's lines act on the simulated chamber.
#include "drivers/command_set_server.hpp"

#include <gtest/gtest.h>

#include "../acutrol/acutrol_test_support.hpp"
#include "drivers/line_session.hpp"

namespace calstand::drivers::line {
namespace {

using namespace std::chrono_literals;
using test::RunningWorld;

TEST(CommandSetHandler, AnswersTheAcutrolStyleSetAsTheTableServerDoes) {
  RunningWorld world{50.0};
  SimTableBackend by_hand_backend{world.world(), world.mutex()};
  SimTableBackend by_set_backend{world.world(), world.mutex()};
  CommandSetHandler by_set(*builtin_command_set("acutrol-style"), by_set_backend);
  for (const char* line :
       {"*idn?", ":interlock? 1", ":read:status? 2", ":mode:rate 1", ":demand:position 1,10",
        ":stop 1", ":limit 2,R,50,100", ":read:rate? 2"}) {
    const std::string by_hand = handle_command_line(line, by_hand_backend);
    const auto answer = by_set.handle(line);
    ASSERT_TRUE(answer.has_value()) << line;
    // Refusals differ in code (the set's error format has one code); both must be refusals.
    if (by_hand.rfind("ERR", 0) == 0) {
      EXPECT_EQ(answer->rfind("ERR", 0), 0u) << line << ": " << *answer;
    } else {
      EXPECT_EQ(*answer, by_hand) << line;
    }
  }
  EXPECT_EQ(by_set.handle("hello")->rfind("ERR 500 unknown command", 0), 0u);
  EXPECT_EQ(by_set.handle(":demand:rate 1,fast")->rfind("ERR 500 rate_dps", 0), 0u);
  EXPECT_FALSE(by_set.handle("").has_value());
}

TEST(CommandSetHandler, ALineSessionDrivesTheSimulatedTableThroughTheServedSet) {
  RunningWorld world{50.0};
  SimTableBackend backend{world.world(), world.mutex()};
  auto handler =
      std::make_shared<CommandSetHandler>(*builtin_command_set("acutrol-style"), backend);
  auto server = make_command_set_server(handler, {});
  server->start();
  core::VirtualClock clock;
  FaultCounters counters;
  EventQueue events;
  TcpOptions o;
  o.port = server->port();
  LineSession s(*builtin_command_set("acutrol-style"), std::make_unique<TcpClient>(o), "tcp", 500ms,
                "table controller", clock, counters, events);
  Arguments move;
  move.texts["axis"] = "2";
  move.numbers["angle_deg"] = 45.0;
  ASSERT_TRUE(s.run("position", move).ok());
  Arguments axis;
  axis.texts["axis"] = "2";
  EXPECT_TRUE(test::eventually([&] {
    const Outcome st = s.run("read_status", axis);
    const Outcome pos = s.run("read_position", axis);
    return st.ok() && pos.ok() && st.truth("in_position") == true &&
           std::abs(pos.number("angle_deg") - 45.0) < 1e-3;
  }));
  const Outcome status = s.run("read_status", axis);
  EXPECT_EQ(status.text("mode"), "position");
  const Outcome interlock = s.run("read_interlock", axis);
  ASSERT_TRUE(interlock.ok()) << interlock.message;
  EXPECT_EQ(interlock.truth("open"), false);
  backend.open_interlock(acutrol::kInnerAxis, "door open");
  Arguments rate = axis;
  rate.numbers["rate_dps"] = 10.0;
  const Outcome refused = s.run("rate", rate);
  EXPECT_EQ(refused.kind, Outcome::Kind::kRefused);
  EXPECT_NE(refused.message.find("interlock"), std::string::npos) << refused.message;
  server->stop();
}

}  // namespace
}  // namespace calstand::drivers::line

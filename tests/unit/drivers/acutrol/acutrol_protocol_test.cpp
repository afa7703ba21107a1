#include "drivers/acutrol_protocol.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

namespace calstand::drivers::acutrol {
namespace {

int code_of(const CommandParse& p) { return p.command ? 0 : p.error.code; }
constexpr int code(ErrorCode c) { return static_cast<int>(c); }

TEST(AcutrolProtocol, FormatsTheRequiredCommands) {
  EXPECT_EQ(format_command({CommandKind::kModeRate, 1}), ":mode:rate 1");
  EXPECT_EQ(format_command({CommandKind::kModePosition, 2}), ":mode:position 2");
  EXPECT_EQ(format_command({CommandKind::kDemandRate, 1, 10.0}), ":demand:rate 1,10.000000");
  EXPECT_EQ(format_command({CommandKind::kDemandPosition, 2, 90.0}),
            ":demand:position 2,90.000000");
  EXPECT_EQ(format_command({CommandKind::kReadPosition, 1}), ":read:pos? 1");
  EXPECT_EQ(format_command({CommandKind::kReadRate, 1}), ":read:rate? 1");
  EXPECT_EQ(format_command({CommandKind::kReadStatus, 2}), ":read:status? 2");
  EXPECT_EQ(format_command({CommandKind::kInterlockQuery, 1}), ":interlock? 1");
  EXPECT_EQ(format_command({CommandKind::kInterlockClose, 1}), ":interlock:close 1");
  EXPECT_EQ(format_command({CommandKind::kLimit, 1, 300.0, 200.0}),
            ":limit 1,R,300.000000,200.000000");
  EXPECT_EQ(format_command({CommandKind::kStop, 2}), ":stop 2");
  EXPECT_EQ(format_command({CommandKind::kIdentify, 0}), "*idn?");
}

TEST(AcutrolProtocol, EveryFormattedCommandParsesBack) {
  const std::vector<Command> commands{
      {CommandKind::kIdentify, 0},
      {CommandKind::kModeRate, 1},
      {CommandKind::kModePosition, 2},
      {CommandKind::kDemandRate, 1, -12.5},
      {CommandKind::kDemandPosition, 2, 179.9999},
      {CommandKind::kReadPosition, 1},
      {CommandKind::kReadRate, 2},
      {CommandKind::kReadStatus, 1},
      {CommandKind::kInterlockQuery, 2},
      {CommandKind::kInterlockClose, 1},
      {CommandKind::kLimit, 2, 400.0, 250.0},
      {CommandKind::kStop, 1},
  };
  for (const auto& c : commands) {
    const auto p = parse_command(format_command(c));
    ASSERT_TRUE(p.command) << format_command(c) << ": " << p.error.text;
    EXPECT_EQ(p.command->kind, c.kind);
    EXPECT_EQ(p.command->axis, c.axis);
    EXPECT_DOUBLE_EQ(p.command->value, c.value);
    EXPECT_DOUBLE_EQ(p.command->value2, c.value2);
  }
}

TEST(AcutrolProtocol, ParsingIgnoresCaseBlanksAndCarriageReturn) {
  const auto p = parse_command("  :DEMAND:Rate\t 2 , +10.5 \r");
  ASSERT_TRUE(p.command) << p.error.text;
  EXPECT_EQ(p.command->kind, CommandKind::kDemandRate);
  EXPECT_EQ(p.command->axis, 2);
  EXPECT_DOUBLE_EQ(p.command->value, 10.5);
  ASSERT_TRUE(parse_command(":LIMIT 1,r,100,50").command);
}

TEST(AcutrolProtocol, BadCommandsGetTheirErrorCode) {
  EXPECT_EQ(code_of(parse_command("")), code(ErrorCode::kUnknownCommand));
  EXPECT_EQ(code_of(parse_command(":mode:turbo 1")), code(ErrorCode::kUnknownCommand));
  EXPECT_EQ(code_of(parse_command(":mode:rate")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command(":mode:rate 1,2")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command(":demand:rate 1")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command(":demand:rate 1,fast")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command(":demand:rate 1,10x")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command(":demand:rate 1,nan")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command(":demand:position 1,inf")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command(":demand:position 1,1e999")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command(":limit 1,P,10,10")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command(":limit 1,R,-10,10")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command(":limit 1,R,10")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command("*idn? 1")), code(ErrorCode::kBadArgument));
  EXPECT_EQ(code_of(parse_command(std::string(kMaxLineBytes + 1, 'a'))),
            code(ErrorCode::kLineTooLong));
}

TEST(AcutrolProtocol, WrongAxesAreRefusedWithTheAxisCode) {
  for (const char* line :
       {":read:pos? 0", ":read:pos? 3", ":read:pos? -1", ":read:pos? x", ":read:pos? 1.5",
        ":stop 12", ":demand:rate 9,1.0", ":limit 0,R,1,1", ":interlock? 2a"}) {
    const auto p = parse_command(line);
    EXPECT_EQ(code_of(p), code(ErrorCode::kBadAxis)) << line;
    EXPECT_NE(p.error.text.find("not 1 (outer) or 2 (inner)"), std::string::npos) << line;
  }
}

TEST(AcutrolProtocol, RepliesSplitIntoErrorsAndPayloads) {
  const auto ok = parse_reply("OK\r");
  EXPECT_TRUE(is_ok(ok));
  const auto err = parse_reply("ERR 300 axis 1 interlock open: door open");
  ASSERT_TRUE(err.error);
  EXPECT_EQ(err.error->code, 300);
  EXPECT_EQ(err.error->text, "axis 1 interlock open: door open");
  EXPECT_FALSE(is_ok(err));
  // A refusal without a readable code is still a refusal, never data.
  const auto odd = parse_reply("ERR what");
  ASSERT_TRUE(odd.error);
  EXPECT_EQ(odd.error->code, 0);
  EXPECT_FALSE(parse_reply("12.5").error);
  EXPECT_DOUBLE_EQ(*parse_number("-179.999900").value, -179.9999);
  EXPECT_FALSE(parse_number("12.5.3"));
  EXPECT_FALSE(parse_number(""));
  EXPECT_FALSE(parse_number("nan"));
}

TEST(AcutrolProtocol, StatusRoundTripsAndRejectsMalformedReplies) {
  const StatusReply s{WireMode::kFault, false, true, "interlock open: door open, bay 2"};
  const auto back = parse_status(format_status(s));
  ASSERT_TRUE(back) << back.error;
  EXPECT_EQ(back.value->mode, WireMode::kFault);
  EXPECT_FALSE(back.value->settled);
  EXPECT_TRUE(back.value->interlock_open);
  EXPECT_EQ(back.value->fault_text, "interlock open: door open, bay 2");
  const auto plain = parse_status("RATE,1,CLOSED");
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain.value->mode, WireMode::kRate);
  EXPECT_TRUE(plain.value->settled);
  EXPECT_TRUE(plain.value->fault_text.empty());
  for (const char* bad : {"", "RATE", "RATE,1", "SPIN,1,CLOSED", "RATE,2,CLOSED", "RATE,1,AJAR"}) {
    const auto p = parse_status(bad);
    EXPECT_FALSE(p) << bad;
    EXPECT_NE(p.error.find("status reply"), std::string::npos);
  }
  EXPECT_TRUE(parse_interlock("CLOSED").value->open == false);
  const auto open = parse_interlock("OPEN,door open");
  ASSERT_TRUE(open);
  EXPECT_TRUE(open.value->open);
  EXPECT_EQ(open.value->why, "door open");
  EXPECT_FALSE(parse_interlock("MAYBE"));
}

TEST(AcutrolProtocol, ErrorTextIsOneSafeLine) {
  const std::string line =
      format_error(ErrorCode::kController, "bad\nthing\r\x01" + std::string(500, 'x'));
  EXPECT_EQ(line.find('\n'), std::string::npos);
  EXPECT_EQ(line.find('\r'), std::string::npos);
  EXPECT_LE(line.size(), kMaxLineBytes);
  EXPECT_EQ(line.rfind("ERR 500 bad thing", 0), 0u);
}

TEST(LineAssembler, JoinsLinesSplitAcrossReadsAndDropsCarriageReturns) {
  LineAssembler a;
  a.push(":read:p");
  EXPECT_FALSE(a.next());
  a.push("os? 1\r\nOK\n");
  auto first = a.next();
  ASSERT_TRUE(first);
  EXPECT_EQ(first->text, ":read:pos? 1");
  EXPECT_EQ(a.next()->text, "OK");
  EXPECT_FALSE(a.next());
}

TEST(LineAssembler, DiscardsAnOverlongLineOnceAndKeepsTheNext) {
  LineAssembler a;
  a.push(std::string(kMaxLineBytes, 'a') + "\n");      // exactly the limit: kept
  a.push(std::string(kMaxLineBytes, 'b') + "\r\n");    // limit plus CR: kept
  a.push(std::string(kMaxLineBytes + 1, 'c') + "\n");  // one over: overlong
  a.push(std::string(10 * kMaxLineBytes, 'd'));        // huge, terminator later
  EXPECT_LE(a.buffered_bytes(), kMaxLineBytes + 1);    // memory stays bounded
  a.push("\nOK\n");
  auto l = a.next();
  ASSERT_TRUE(l);
  EXPECT_FALSE(l->overlong);
  EXPECT_EQ(l->text.size(), kMaxLineBytes);
  l = a.next();
  EXPECT_FALSE(l->overlong);
  EXPECT_EQ(l->text, std::string(kMaxLineBytes, 'b'));
  EXPECT_TRUE(a.next()->overlong);
  EXPECT_TRUE(a.next()->overlong);
  EXPECT_EQ(a.next()->text, "OK");
}

/// Random lines: printable garbage, raw bytes, valid commands cut short or with a byte changed,
/// and overlong runs. Fixed seeds so a failure reproduces.
std::string random_input(std::mt19937& rng) {
  static const std::vector<std::string> valid{
      ":mode:rate 1",    ":demand:position 2,90.0", ":read:pos? 1",      ":limit 1,R,100,50",
      ":read:status? 2", ":interlock:close 1",      ":demand:rate 1,-5", "*idn?"};
  std::uniform_int_distribution<int> kind(0, 4);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<int> printable(0x20, 0x7e);
  std::string out;
  switch (kind(rng)) {
    case 0: {  // printable garbage
      const int n = std::uniform_int_distribution<int>(0, 80)(rng);
      for (int i = 0; i < n; ++i) out.push_back(static_cast<char>(printable(rng)));
      break;
    }
    case 1: {  // raw bytes, newlines included
      const int n = std::uniform_int_distribution<int>(0, 80)(rng);
      for (int i = 0; i < n; ++i) out.push_back(static_cast<char>(byte(rng)));
      break;
    }
    case 2: {  // a valid command cut short
      const auto& v = valid[std::uniform_int_distribution<std::size_t>(0, valid.size() - 1)(rng)];
      out = v.substr(0, std::uniform_int_distribution<std::size_t>(0, v.size())(rng));
      break;
    }
    case 3: {  // a valid command with one byte changed
      out = valid[std::uniform_int_distribution<std::size_t>(0, valid.size() - 1)(rng)];
      out[std::uniform_int_distribution<std::size_t>(0, out.size() - 1)(rng)] =
          static_cast<char>(byte(rng));
      break;
    }
    default:  // overlong
      out.assign(kMaxLineBytes + std::uniform_int_distribution<std::size_t>(1, 2000)(rng), 'z');
  }
  return out + "\n";
}

TEST(AcutrolProtocol, RandomCorpusNeverCrashesAndEveryLineIsAccountedFor) {
  for (const unsigned seed : {1u, 2u, 3u, 42u}) {
    std::mt19937 rng(seed);
    LineAssembler a;
    std::size_t lines = 0, parsed = 0, refused = 0, overlong = 0, reply_errors = 0;
    for (int i = 0; i < 3000; ++i) {
      const std::string input = random_input(rng);
      a.push(input);
      EXPECT_LE(a.buffered_bytes(), kMaxLineBytes + 1);
      while (auto line = a.next()) {
        ++lines;
        if (line->overlong) {
          ++overlong;
          continue;
        }
        EXPECT_LE(line->text.size(), kMaxLineBytes);
        const auto p = parse_command(line->text);
        if (p.command) {
          ++parsed;
          // Whatever parsed formats back to a line that parses to the same command.
          const auto again = parse_command(format_command(*p.command));
          ASSERT_TRUE(again.command) << format_command(*p.command);
          EXPECT_EQ(again.command->kind, p.command->kind);
        } else {
          ++refused;
          EXPECT_GE(p.error.code, 100);
          EXPECT_FALSE(p.error.text.empty());
          const std::string err = format_error(p.error.code, p.error.text);
          EXPECT_EQ(err.find('\n'), std::string::npos);
        }
        // The client-side parsers take the same garbage as replies.
        const auto r = parse_reply(line->text);
        if (!parse_number(r.payload)) ++reply_errors;
        if (!parse_status(r.payload) && !parse_interlock(r.payload)) ++reply_errors;
      }
    }
    EXPECT_EQ(lines, parsed + refused + overlong) << "seed " << seed;
    EXPECT_GT(refused, 1000u) << "seed " << seed;  // garbage is refused, not taken as commands
    EXPECT_GT(overlong, 300u) << "seed " << seed;
    EXPECT_GT(reply_errors, lines) << "seed " << seed;
  }
}

TEST(AcutrolProtocol, SineCommandsFormatAndParseBackAndRefuseBadArguments) {
  EXPECT_EQ(format_command({CommandKind::kModeSine, 1}), ":mode:sine 1");
  EXPECT_EQ(format_command({CommandKind::kDemandSine, 2, 0.5, 2.0}),
            ":demand:sine 2,0.500000,2.000000");
  const auto p = parse_command(" :DEMAND:SINE 2, 0.25 ,+10 \r");
  ASSERT_TRUE(p.command) << p.error.text;
  EXPECT_EQ(p.command->kind, CommandKind::kDemandSine);
  EXPECT_EQ(p.command->axis, 2);
  EXPECT_DOUBLE_EQ(p.command->value, 0.25);
  EXPECT_DOUBLE_EQ(p.command->value2, 10.0);
  for (const char* bad : {":demand:sine 1,0.5", ":demand:sine 1,0,2", ":demand:sine 1,0.5,-2",
                          ":demand:sine 1,0.5,nan", ":demand:sine 1,0.5,2,3"}) {
    const auto b = parse_command(bad);
    EXPECT_FALSE(b.command) << bad;
    EXPECT_EQ(b.error.code, 101) << bad << ": " << b.error.text;
  }
  const auto status = parse_status("SINE,1,CLOSED");
  ASSERT_TRUE(status) << status.error;
  EXPECT_EQ(status.value->mode, WireMode::kSine);
  EXPECT_EQ(format_status(*status.value), "SINE,1,CLOSED");
}

}  // namespace
}  // namespace calstand::drivers::acutrol

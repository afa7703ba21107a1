// calstandd's event stream read by a standard EventSource client (Node's `eventsource`, an
// implementation of the WHATWG rules that shares no code with calstand): the events arrive with
// their types, ids and data, and a reconnection with Last-Event-ID resumes without loss or
// duplicates. Skipped only when node is not installed; CALSTAND_REQUIRE_SSE_CLIENT (set by
// scripts/run-tests.sh, whose setup-deps installs nodejs and node-eventsource) makes that a
// failure.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "daemon_test_support.hpp"

namespace {

using calstand::testing::ApiClient;
using calstand::testing::DaemonProcess;
using calstand::testing::EventStreamReader;
using calstand::testing::wait_until;

struct ClientEvent {
  int phase = 0;
  std::string type;
  std::string id;
  std::string data;
};

// The sequence number of an EPOCH-SEQ id.
std::uint64_t seq_of(const std::string& id) { return std::stoull(id.substr(id.find('-') + 1)); }

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(DaemonSseClient, AStandardEventSourceReadsTheStreamAndResumesWithLastEventId) {
  if (std::system("node --version > /dev/null 2>&1") != 0) {
    if (std::getenv("CALSTAND_REQUIRE_SSE_CLIENT")) {
      FAIL() << "node is not installed (CALSTAND_REQUIRE_SSE_CLIENT is set: the test command "
                "expects scripts/setup-deps.sh to have installed nodejs and node-eventsource)";
    }
    GTEST_SKIP() << "node is not installed: the standard-client check of GET /events is skipped "
                    "(scripts/setup-deps.sh installs nodejs and node-eventsource)";
  }
  const std::string dir = calstand::testing::fresh_dir("sse-client");
  DaemonProcess daemon(dir + "/station.db", dir + "/calstandd.log");
  ASSERT_GT(daemon.port(), 0) << read_file(dir + "/calstandd.log");
  // calstand's own decoder reads the same stream all along, to compare with.
  EventStreamReader ours(daemon.port());
  ASSERT_TRUE(
      wait_until([&] { return ours.saw([](const auto& m) { return m.type == "station"; }); }));

  // Debian installs node modules in /usr/share/nodejs, which a node not built by Debian does
  // not search by itself.
  const std::string command =
      std::string("CALSTAND_TOKEN=") + calstand::testing::kTestToken +
      " NODE_PATH=/usr/share/nodejs${NODE_PATH:+:$NODE_PATH} node " CALSTAND_SOURCE_DIR
      "/tests/integration/sse_standard_client.js http://127.0.0.1:" +
      std::to_string(daemon.port()) + " '{\"capture_s\": 5}' 6 2> " + dir + "/client.err";
  FILE* pipe = ::popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.append(buffer, n);
  const int status = ::pclose(pipe);
  const std::string err = read_file(dir + "/client.err");
  ASSERT_EQ(status, 0) << "client: " << err << "\noutput:\n" << out;

  std::vector<ClientEvent> events;
  std::int64_t run = 0;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);) {
    const auto j = nlohmann::json::parse(line, nullptr, false);
    ASSERT_TRUE(j.is_object()) << line;
    if (j.contains("done")) {
      run = j["run"].get<std::int64_t>();
      continue;
    }
    events.push_back({j["phase"].get<int>(), j["type"].get<std::string>(),
                      j["id"].get<std::string>(), j["data"].get<std::string>()});
  }
  ASSERT_GT(run, 0) << out << err;
  ASSERT_FALSE(events.empty());

  // Each connection starts with the station snapshot, which carries no id: the first has none
  // yet, the second still has the one the client reconnected with.
  std::string reconnected_with;
  for (std::size_t i = 0; i < events.size(); ++i) {
    if (events[i].phase == 2) {
      ASSERT_GT(i, 0u);
      reconnected_with = events[i - 1].id;
      EXPECT_EQ(events[i].type, "station");
      EXPECT_EQ(events[i].id, reconnected_with);
      break;
    }
  }
  EXPECT_EQ(events.front().type, "station");
  EXPECT_EQ(events.front().id, "");
  ASSERT_FALSE(reconnected_with.empty()) << out;

  // Ids in order, each once, with nothing missing across the reconnection; no gap message.
  std::vector<std::uint64_t> seqs;
  for (const auto& e : events) {
    EXPECT_NE(e.type, "gap") << e.data;
    EXPECT_TRUE(nlohmann::json::accept(e.data)) << e.type << ": " << e.data;
    if (e.type == "station") continue;
    ASSERT_FALSE(e.id.empty()) << e.type << ": " << e.data;
    seqs.push_back(seq_of(e.id));
  }
  ASSERT_GE(seqs.size(), 6u);
  for (std::size_t i = 1; i < seqs.size(); ++i) {
    EXPECT_EQ(seqs[i], seqs[i - 1] + 1) << "message " << i << " of the two connections";
  }

  // The same types, ids and data as calstand's decoder read from its own connection.
  ASSERT_TRUE(wait_until([&] {
    return ours.saw([&](const auto& m) {
      return m.type == "run" && m.data.value("run", 0) == run &&
             m.data.value("state", "") == "completed";
    });
  }));
  std::map<std::string, EventStreamReader::Message> by_id;
  for (const auto& m : ours.messages()) {
    if (m.type != "station" && !m.id.empty()) by_id.emplace(m.id, m);
  }
  for (const auto& e : events) {
    if (e.type == "station") continue;
    const auto it = by_id.find(e.id);
    ASSERT_NE(it, by_id.end()) << e.id;
    EXPECT_EQ(it->second.type, e.type) << e.id;
    EXPECT_EQ(it->second.data, nlohmann::json::parse(e.data)) << e.id;
  }

  // Every step of the run was seen to complete exactly once.
  ApiClient api(daemon.port());
  const auto steps = api.get("/runs/" + std::to_string(run) + "/steps");
  ASSERT_EQ(steps.status, 200);
  std::map<std::int64_t, int> completions;
  for (const auto& e : events) {
    if (e.type != "step") continue;
    const auto data = nlohmann::json::parse(e.data);
    if (data["run"] == run && data["status"] == "completed")
      ++completions[data["step"].get<std::int64_t>()];
  }
  ASSERT_FALSE(steps.body.empty());
  for (const auto& s : steps.body) {
    EXPECT_EQ(completions[s["index"].get<std::int64_t>()], 1) << s.dump();
  }
}

}  // namespace

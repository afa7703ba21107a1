// Load bench of calstandd's control API (issue 7): an in-process daemon on an ephemeral
// loopback port with a simulated station of two IMUs at 1 kHz; 20 clients poll GET /runs/ID
// and one reads GET /events while a six-position run captures. Prints the status latency
// figures (p50, p95, p99, max) and checks that no sample was dropped: every capture of both
// IMUs contiguous in sequence and of the expected length. Exit 0 when nothing was dropped.
//
//   calstand_daemon_load_bench [--capture-s S] [--clients N]
#include <Eigen/Core>  // before httplib.h: its <resolv.h> defines a macro `_res`, a name Eigen uses
#include <fmt/format.h>
#include <httplib.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "daemon/api/api_server.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/run_service.hpp"
#include "sim/sim_world.hpp"
#include "sim/spec_sheet.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"

namespace {

using namespace calstand;
using Clock = std::chrono::steady_clock;

// The default station with two LN200-class IMUs whose output rate is 1 kHz.
core::StationConfig two_imus_at_1khz(const std::filesystem::path& dir) {
  nlohmann::json spec = *sim::builtin_spec("ln200");
  spec["output"]["sample_rate"] = "1000 Hz";
  std::ofstream(dir / "ln200-1khz.spec.json") << spec.dump(2);
  nlohmann::json station = sim::default_station().to_json();
  station["name"] = "load-bench";
  station["imus"] = nlohmann::json::array();
  for (const char* name : {"imu0", "imu1"}) {
    station["imus"].push_back({{"name", name}, {"backend", "sim"}, {"spec_file", "ln200-1khz.spec.json"}});
  }
  return core::StationConfig::from_json(station, (dir / "station.json").string(), dir.string());
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
}

}  // namespace

int main(int argc, char** argv) {
  double capture_s = 60.0;
  int clients = 20;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--capture-s") capture_s = std::stod(argv[i + 1]);
    if (a == "--clients") clients = std::stoi(argv[i + 1]);
  }
  const auto dir = std::filesystem::temp_directory_path() / fmt::format("calstandd-load-{}", getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string db = (dir / "station.db").string();

  daemon::service::EventHub hub;
  daemon::service::RunService service({two_imus_at_1khz(dir), db, daemon::service::RecoveryPolicy::kAuto}, hub);
  daemon::api::ApiOptions api_options;
  api_options.port = 0;
  api_options.threads = clients + 8;
  daemon::api::ApiServer server(service, hub, api_options);
  const int port = server.start();
  service.start();

  httplib::Client submitter("127.0.0.1", port);
  const nlohmann::json body = {{"procedure", "six-position"}, {"parameters", {{"capture_s", capture_s}}}};
  const auto submitted = submitter.Post("/runs", body.dump(), "application/json");
  if (!submitted || submitted->status != 201) {
    fmt::print(stderr, "submit failed\n");
    return 1;
  }
  const auto run = nlohmann::json::parse(submitted->body)["id"].get<std::int64_t>();
  const std::string path = fmt::format("/runs/{}", run);

  std::atomic<bool> done{false};
  std::mutex mutex;
  std::vector<double> latencies_ms;
  std::atomic<int> failures{0};
  std::vector<std::thread> pollers;
  const auto t0 = Clock::now();
  for (int c = 0; c < clients; ++c) {
    pollers.emplace_back([&] {
      httplib::Client client("127.0.0.1", port);
      client.set_keep_alive(true);
      std::vector<double> mine;
      while (!done) {
        const auto start = Clock::now();
        const auto res = client.Get(path.c_str());
        mine.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
        if (!res || res->status != 200) {
          ++failures;
        } else if (nlohmann::json::parse(res->body)["status"] == "completed") {
          done = true;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      std::lock_guard lock(mutex);
      latencies_ms.insert(latencies_ms.end(), mine.begin(), mine.end());
    });
  }
  std::atomic<int> sse_messages{0};
  httplib::Client sse("127.0.0.1", port);
  std::thread reader([&] {
    sse.Get("/events", [&](const char* data, std::size_t n) {
      const std::string_view chunk(data, n);
      for (auto at = chunk.find("event: "); at != std::string_view::npos; at = chunk.find("event: ", at + 1)) {
        ++sse_messages;
      }
      return !done;
    });
  });
  for (auto& t : pollers) t.join();
  const double wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  sse.stop();
  reader.join();
  service.stop("bench over");
  server.stop();

  // No dropped samples: each capture of each IMU contiguous and about capture_s * 1000 long.
  store::Database database(db);
  bool dropped = false;
  std::size_t total = 0;
  for (const auto& s : store::RunStore(database).load_steps(run)) {
    if (s.kind != "capture") continue;
    for (const char* imu : {"imu0", "imu1"}) {
      const auto samples = store::read_samples(database, run, s.index, imu);
      total += samples.size();
      std::size_t gaps = 0;
      for (std::size_t k = 1; k < samples.size(); ++k) {
        if (samples[k].sequence != (samples[k - 1].sequence + 1) % 65536) ++gaps;
      }
      const double expected = capture_s * 1000.0;
      if (gaps > 0 || std::abs(static_cast<double>(samples.size()) - expected) > 101.0) {
        dropped = true;
        fmt::print("step {} {}: {} samples (expected {:.0f}), {} sequence gaps\n", s.index, imu,
                   samples.size(), expected, gaps);
      }
    }
  }
  fmt::print("run {}: {} samples of 2 IMUs at 1 kHz in {:.2f} s wall; {} clients, {} status requests "
             "({} failed), {} SSE messages\n",
             run, total, wall_s, clients, latencies_ms.size(), failures.load(), sse_messages.load());
  fmt::print("GET {} latency [ms]: p50 {:.2f}  p95 {:.2f}  p99 {:.2f}  max {:.2f}\n", path,
             percentile(latencies_ms, 0.5), percentile(latencies_ms, 0.95), percentile(latencies_ms, 0.99),
             percentile(latencies_ms, 1.0));
  fmt::print("dropped samples: {}\n", dropped ? "YES" : "none");
  std::filesystem::remove_all(dir);
  return dropped || failures > 0 ? 1 : 0;
}

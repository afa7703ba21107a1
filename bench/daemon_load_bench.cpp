// Load bench of calstandd's control API (issue 7): an in-process daemon on an ephemeral
// loopback port with a station of two IMUs at 1 kHz; 20 clients poll GET /runs/ID and one
// reads GET /events while a six-position run captures. Prints the status latency figures
// (p50, p95, p99, max), the live messages the stream reader got, and checks that no sample
// was dropped: every capture of both IMUs contiguous in sequence and of the expected length.
// Exit 0 when nothing was dropped and no request failed.
//
// Two stations:
//   default      the in-process simulator on its virtual clock: the run goes as fast as the
//                CPU allows (samples arrive many times faster than 1 kHz: the writer's worst
//                case, with the pollers competing for the two cores);
//   --drivers    the real drivers against the protocol simulator (`calstand sim-station`) in
//                real time (--time-scale 1): the table over TCP, the chamber over Modbus TCP,
//                both IMUs' 1 kHz frames over pseudo-terminals, as in a lab.
//
//   calstand_daemon_load_bench [--capture-s S] [--clients N] [--drivers] [--time-scale K]
// clang-format off
#include <Eigen/Core>  // before httplib.h: its <resolv.h> defines a macro `_res`, a name Eigen uses
#include <httplib.h>
// clang-format on
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "daemon/api/api_server.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/run_service.hpp"
#include "drivers/protocol_simulator.hpp"
#include "sim/sim_world.hpp"
#include "sim/spec_sheet.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"
#include "wire/sse_decoder.hpp"

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
    station["imus"].push_back(
        {{"name", name}, {"backend", "sim"}, {"spec_file", "ln200-1khz.spec.json"}});
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
  double capture_s = 0.0;  // default below: 60 s simulated, 10 s through the drivers
  int clients = 20;
  bool through_drivers = false;
  double time_scale = 1.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--drivers") {
      through_drivers = true;
    } else if (a == "--capture-s" && has_value) {
      capture_s = std::stod(argv[++i]);
    } else if (a == "--clients" && has_value) {
      clients = std::stoi(argv[++i]);
    } else if (a == "--time-scale" && has_value) {
      time_scale = std::stod(argv[++i]);
    } else {
      fmt::print(stderr, "usage: {} [--capture-s S] [--clients N] [--drivers] [--time-scale K]\n",
                 argv[0]);
      return 2;
    }
  }
  if (capture_s <= 0.0) capture_s = through_drivers ? 10.0 : 60.0;
  const auto dir =
      std::filesystem::temp_directory_path() / fmt::format("calstandd-load-{}", getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string db = (dir / "station.db").string();

  const core::StationConfig simulated = two_imus_at_1khz(dir);
  std::unique_ptr<drivers::ProtocolSimulator> lab;
  core::StationConfig station = simulated;
  if (through_drivers) {
    drivers::ProtocolSimOptions options;
    options.time_scale = time_scale;
    options.f4_rtu = false;  // the chamber over Modbus TCP only
    lab = std::make_unique<drivers::ProtocolSimulator>(simulated, options);
    lab->start();
    station = lab->client_station();
  }
  daemon::service::EventHub hub;
  daemon::service::RunService service({station, db, daemon::service::RecoveryPolicy::kAuto}, hub);
  daemon::api::ApiOptions api_options;
  api_options.port = 0;
  api_options.threads = clients + 8;
  daemon::api::ApiServer server(service, hub, api_options);
  const int port = server.start();
  service.start();

  // The stream reader is connected (its greeting read) before the run is submitted, and reads
  // until the run's completion: it must see every step of the run.
  std::map<std::string, int> sse_by_type;  // written by the reader, read after it is joined
  std::atomic<bool> sse_greeted{false};
  std::atomic<bool> sse_saw_end{false};
  httplib::Client sse("127.0.0.1", port);
  sse.set_read_timeout(10, 0);
  std::thread reader([&] {
    wire::SseDecoder parser([&](const wire::SseEvent& m) {
      ++sse_by_type[m.type];
      if (m.type == "station") sse_greeted = true;
      if (m.type == "run" && m.data.find("\"completed\"") != std::string::npos) sse_saw_end = true;
      return !sse_saw_end;
    });
    sse.Get("/events", [&](const char* data, std::size_t n) { return parser.feed({data, n}); });
  });
  for (int i = 0; i < 1000 && !sse_greeted; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));

  httplib::Client submitter("127.0.0.1", port);
  const nlohmann::json body = {{"procedure", "six-position"},
                               {"parameters", {{"capture_s", capture_s}}}};
  const auto submitted = submitter.Post("/runs", body.dump(), "application/json");
  if (!sse_greeted || !submitted || submitted->status != 201) {
    fmt::print(stderr, "{}\n", sse_greeted ? "submit failed" : "the live stream did not open");
    sse.stop();
    reader.join();
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
      client.set_tcp_nodelay(true);
      std::vector<double> mine;
      while (!done) {
        const auto start = Clock::now();
        const auto res = client.Get(path.c_str());
        mine.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
        if (!res || res->status != 200) {
          ++failures;
        } else if (const std::string status = nlohmann::json::parse(res->body)["status"];
                   status == "completed" || status == "aborted" || status == "failed") {
          done = true;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      std::lock_guard lock(mutex);
      latencies_ms.insert(latencies_ms.end(), mine.begin(), mine.end());
    });
  }
  for (auto& t : pollers) t.join();
  const double wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  // The run's last message may still be on its way to the stream reader.
  for (int i = 0; i < 500 && !sse_saw_end; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  sse.stop();
  reader.join();
  service.stop("bench over");
  server.stop();
  if (lab) lab->stop();

  // No dropped samples: each capture of each IMU contiguous and about capture_s * 1000 long.
  store::Database database(db);
  const auto summary = store::RunStore(database).load_run(run).summary;
  if (summary.status != "completed") {
    fmt::print("run {} {}: {}\n", run, summary.status, summary.exit_reason);
    return 1;
  }
  bool dropped = false;
  std::size_t total = 0;
  const auto steps = store::RunStore(database).load_steps(run);
  for (const auto& s : steps) {
    if (s.kind != "capture") continue;
    for (const char* imu : {"imu0", "imu1"}) {
      const auto samples = store::read_samples(database, run, s.index, imu);
      total += samples.size();
      std::size_t gaps = 0;
      // Low 16 bits: the simulated IMU's counter wraps at 2^16, a serial frame's at 2^32.
      for (std::size_t k = 1; k < samples.size(); ++k) {
        if (((samples[k].sequence - samples[k - 1].sequence) & 0xFFFFu) != 1u) ++gaps;
      }
      const double expected = capture_s * 1000.0;
      if (gaps > 0 || std::abs(static_cast<double>(samples.size()) - expected) > 101.0) {
        dropped = true;
        fmt::print("step {} {}: {} samples (expected {:.0f}), {} sequence gaps\n", s.index, imu,
                   samples.size(), expected, gaps);
      }
    }
  }
  std::string by_type;
  int sse_total = 0;
  for (const auto& [type, count] : sse_by_type) {
    by_type += fmt::format("{}{} {}", by_type.empty() ? "" : ", ", count, type);
    sse_total += count;
  }
  fmt::print(
      "{}: run {}: {} samples of 2 IMUs at 1 kHz in {:.2f} s wall; {} clients, {} status requests "
      "({} failed)\n",
      through_drivers ? fmt::format("real drivers, time scale {}", time_scale)
                      : "simulated station",
      run, total, wall_s, clients, latencies_ms.size(), failures.load());
  // Every step starts and completes once (no capture is repeated on a healthy station).
  const bool every_step_seen = sse_by_type["step"] >= static_cast<int>(2 * steps.size());
  fmt::print(
      "SSE reader: {} messages ({}){}{}\n", sse_total, by_type,
      sse_saw_end ? "" : "; the run's completion NOT seen",
      every_step_seen ? "" : fmt::format("; fewer step messages than 2 x {} steps", steps.size()));
  fmt::print("GET {} latency [ms]: p50 {:.2f}  p95 {:.2f}  p99 {:.2f}  max {:.2f}\n", path,
             percentile(latencies_ms, 0.5), percentile(latencies_ms, 0.95),
             percentile(latencies_ms, 0.99), percentile(latencies_ms, 1.0));
  fmt::print("dropped samples: {}\n", dropped ? "YES" : "none");
  std::filesystem::remove_all(dir);
  return dropped || failures > 0 || !sse_saw_end || !every_step_seen ? 1 : 0;
}

// Load bench of calstandd's control API and capture path (issues 7 and 16): an in-process
// daemon on an ephemeral loopback port with a station of N IMUs at R Hz (default 2 at 1 kHz);
// C clients (default 20) poll GET /runs/ID and K readers (default 2) read GET /events while a
// six-position run captures. Prints the status latency figures (p50, p95, p99, max), the live
// messages each stream reader got, the capture writer's queue high-water mark, and checks that
// no sample was dropped anywhere between the IMU and the database. Ends with one JSON line of
// the figures. Exit 0 when nothing was dropped, no request failed and every reader saw the run.
//
// Two stations:
//   default      the in-process simulator on its virtual clock: the run goes as fast as the
//                CPU allows (samples arrive many times faster than real time: the writer's
//                worst case, with the pollers competing for the cores);
//   --drivers    the real drivers against the protocol simulator (`calstand sim-station`) in
//                real time (--time-scale 1): the table over TCP, the chamber over Modbus TCP,
//                every IMU's frames over its own pseudo-terminal, as in a lab.
//
//   calstand_daemon_load_bench [--drivers] [--imus N] [--rate-hz R] [--clients C] [--readers K]
//                              [--capture-s S | --station-s T] [--time-scale X]
// --capture-s is the length of each of the six captures; --station-s T asks for T seconds of
// station time in captures alone (each capture T/6 s), e.g. --station-s 600 for ten minutes.
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
#include "daemon/run_engine.hpp"
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

// The default station with `imus` LN200-class IMUs whose output rate is `rate_hz`.
core::StationConfig station_of(const std::filesystem::path& dir, int imus, double rate_hz) {
  nlohmann::json spec = *sim::builtin_spec("ln200");
  spec["output"]["sample_rate"] = fmt::format("{} Hz", rate_hz);
  std::ofstream(dir / "ln200-bench.spec.json") << spec.dump(2);
  nlohmann::json station = sim::default_station().to_json();
  station["name"] = "load-bench";
  station["imus"] = nlohmann::json::array();
  for (int i = 0; i < imus; ++i) {
    station["imus"].push_back({{"name", fmt::format("imu{}", i)},
                               {"backend", "sim"},
                               {"spec_file", "ln200-bench.spec.json"}});
  }
  return core::StationConfig::from_json(station, (dir / "station.json").string(), dir.string());
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
}

// Samples missing between consecutive sequence numbers. The low 16 bits suffice: the
// simulated IMU's counter wraps at 2^16, a serial frame's at 2^32, and a gap of 65536 or more
// would also show in the sample count.
std::uint64_t missing_between(std::uint32_t previous, std::uint32_t next) {
  return (((next - previous) & 0xFFFFu) + 0xFFFFu) & 0xFFFFu;
}

// One reader of GET /events until the run completes, counting messages by type.
struct StreamReader {
  std::map<std::string, int> by_type;  // written by the thread, read after it is joined
  std::atomic<bool> greeted{false};
  std::atomic<bool> saw_end{false};
  std::unique_ptr<httplib::Client> client;
  std::thread thread;

  explicit StreamReader(int port) : client(std::make_unique<httplib::Client>("127.0.0.1", port)) {
    client->set_read_timeout(10, 0);
    thread = std::thread([this] {
      wire::SseDecoder parser([this](const wire::SseEvent& m) {
        ++by_type[m.type];
        if (m.type == "station") greeted = true;
        if (m.type == "run" && m.data.find("\"completed\"") != std::string::npos) saw_end = true;
        return !saw_end;
      });
      client->Get("/events", [&](const char* data, std::size_t n) {
        return parser.feed({data, n});
      });
    });
  }
  void stop() {
    client->stop();
    if (thread.joinable()) thread.join();
  }
};

}  // namespace

int main(int argc, char** argv) {
  double capture_s = 0.0;  // default below: 60 s simulated, 10 s through the drivers
  double station_s = 0.0;  // when given: capture_s = station_s / 6
  int clients = 20;
  int readers = 2;
  int imus = 2;
  double rate_hz = 1000.0;
  bool through_drivers = false;
  double time_scale = 1.0;
  bool usage = false;
  for (int i = 1; i < argc && !usage; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--drivers") {
      through_drivers = true;
    } else if (a == "--capture-s" && has_value) {
      capture_s = std::stod(argv[++i]);
    } else if (a == "--station-s" && has_value) {
      station_s = std::stod(argv[++i]);
    } else if (a == "--clients" && has_value) {
      clients = std::stoi(argv[++i]);
    } else if (a == "--readers" && has_value) {
      readers = std::stoi(argv[++i]);
    } else if (a == "--imus" && has_value) {
      imus = std::stoi(argv[++i]);
    } else if (a == "--rate-hz" && has_value) {
      rate_hz = std::stod(argv[++i]);
    } else if (a == "--time-scale" && has_value) {
      time_scale = std::stod(argv[++i]);
    } else {
      usage = true;
    }
  }
  if (usage || imus < 1 || readers < 1 || clients < 1 || !(rate_hz > 0.0) ||
      (capture_s > 0.0 && station_s > 0.0)) {
    fmt::print(stderr,
               "usage: {} [--drivers] [--imus N] [--rate-hz R] [--clients C] [--readers K]\n"
               "       [--capture-s S | --station-s T] [--time-scale X]\n",
               argv[0]);
    return 2;
  }
  constexpr int kCaptures = 6;                           // six-position: one capture per position
  const double tick_s = daemon::EngineOptions{}.tick_s;  // the engine's control tick [s]
  if (station_s > 0.0) capture_s = station_s / kCaptures;
  if (capture_s <= 0.0) capture_s = through_drivers ? 10.0 : 60.0;
  const auto dir =
      std::filesystem::temp_directory_path() / fmt::format("calstandd-load-{}", getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string db = (dir / "station.db").string();

  const core::StationConfig simulated = station_of(dir, imus, rate_hz);
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
  api_options.threads = clients + readers + 8;
  daemon::api::ApiServer server(service, hub, api_options);
  const int port = server.start();
  service.start();

  // The stream readers are connected (their greeting read) before the run is submitted, and
  // read until the run's completion: each must see every step of the run.
  std::vector<std::unique_ptr<StreamReader>> streams;
  for (int r = 0; r < readers; ++r) streams.push_back(std::make_unique<StreamReader>(port));
  const auto all_greeted = [&] {
    return std::all_of(streams.begin(), streams.end(),
                       [](const auto& r) { return r->greeted.load(); });
  };
  for (int i = 0; i < 1000 && !all_greeted(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));

  if (!all_greeted()) {
    fmt::print(stderr, "a live stream did not open\n");
    for (auto& r : streams) r->stop();
    return 1;
  }
  httplib::Client submitter("127.0.0.1", port);
  const nlohmann::json body = {{"procedure", "six-position"},
                               {"parameters", {{"capture_s", capture_s}}}};
  const auto submitted = submitter.Post("/runs", body.dump(), "application/json");
  if (!submitted || submitted->status != 201) {
    fmt::print(stderr, "submit failed\n");
    for (auto& r : streams) r->stop();
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
  // The run's last message may still be on its way to the stream readers.
  const auto all_saw_end = [&] {
    return std::all_of(streams.begin(), streams.end(),
                       [](const auto& r) { return r->saw_end.load(); });
  };
  for (int i = 0; i < 500 && !all_saw_end(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  for (auto& r : streams) r->stop();
  service.stop("bench over");
  server.stop();
  if (lab) lab->stop();

  store::Database database(db);
  const auto record = store::RunStore(database).load_run(run);
  if (record.summary.status != "completed") {
    fmt::print("run {} {}: {}\n", run, record.summary.status, record.summary.exit_reason);
    return 1;
  }
  const double run_station_s = record.started_clock_s && record.ended_clock_s
                                   ? *record.ended_clock_s - *record.started_clock_s
                                   : 0.0;

  // Dropped samples, counted three independent ways (a loss may show in more than one):
  //  - in the stored data: every capture of every IMU holds consecutive sequence numbers, and
  //    as many samples as its station time at the IMU's rate, less at most one control tick
  //    (EngineOptions::tick_s) of samples: those stamped before the capture's end that were still
  //    on the line when it closed. More than that missing means samples stalled or vanished;
  //  - as the engine saw the streams during the whole run (its "sequence gap" fault events:
  //    lost frames on the line, CRC failures, driver buffer overflows);
  //  - refused by the capture writer (queue full).
  // A repeated capture fails the bench as well: the repeat hides what the first attempt lost.
  std::uint64_t total = 0;
  double expected_total = 0.0;
  std::uint64_t stored_gaps = 0;       // samples missing inside the stored captures
  std::uint64_t stored_shortfall = 0;  // samples missing at the ends beyond the window cut
  double worst_count_error = 0.0;      // largest |stored - expected| of a capture [samples]
  int repeated_captures = 0;
  std::vector<std::string> device_names;
  for (int i = 0; i < imus; ++i) device_names.push_back(fmt::format("imu{}", i));
  for (const auto& s : record.steps) {
    if (s.kind != "capture") continue;
    if (s.attempts > 1) repeated_captures += s.attempts - 1;
    const double duration_s =
        s.started_clock_s && s.ended_clock_s ? *s.ended_clock_s - *s.started_clock_s : capture_s;
    for (const auto& imu : device_names) {
      const auto samples = store::read_samples(database, run, s.index, imu);
      total += samples.size();
      const double expected = capture_s * rate_hz;
      expected_total += expected;
      std::uint64_t missing = 0;
      for (std::size_t k = 1; k < samples.size(); ++k) {
        missing += missing_between(samples[k - 1].sequence, samples[k].sequence);
      }
      stored_gaps += missing;
      const double count_error = static_cast<double>(samples.size()) - expected;
      worst_count_error = std::max(worst_count_error, std::abs(count_error));
      const double in_flight = tick_s * rate_hz;
      if (-count_error > in_flight) {
        stored_shortfall += static_cast<std::uint64_t>(-count_error - in_flight);
      }
      if (missing > 0 || -count_error > in_flight) {
        fmt::print("step {} {}: {} samples (expected {:.0f} in {:.3f} s), {} missing in gaps\n",
                   s.index, imu, samples.size(), expected, duration_s, missing);
      }
    }
  }
  std::uint64_t stream_gap_samples = 0;  // engine's sequence gap events, whole run
  std::uint64_t writer_refused = 0;
  std::uint64_t writer_high_water = 0;
  std::uint64_t writer_capacity = 0;
  bool writer_summary = false;
  int fault_events = 0;
  for (const auto& e : record.events) {
    if (e.kind == store::EventKind::kFault) ++fault_events;
    if (e.kind == store::EventKind::kFault && e.message.rfind("sequence gap: ", 0) == 0) {
      stream_gap_samples += std::stoull(e.message.substr(14));
    }
    if (e.source == "capture_writer" && e.kind == store::EventKind::kInfo && e.detail.is_object()) {
      writer_summary = true;
      writer_high_water = e.detail.value("queue_high_water", std::uint64_t{0});
      writer_capacity = e.detail.value("queue_capacity", std::uint64_t{0});
      writer_refused += e.detail.value("dropped_queue_full", std::uint64_t{0});
    }
    if (e.kind == store::EventKind::kFault)
      fmt::print("fault event at {:.3f} s: {}: {}\n", e.time_s, e.source, e.message);
  }
  const std::uint64_t dropped =
      stored_gaps + stored_shortfall + stream_gap_samples + writer_refused;

  std::string by_type;
  int sse_total = 0;
  bool every_step_seen = true;
  for (std::size_t r = 0; r < streams.size(); ++r) {
    auto& reader = *streams[r];
    std::string mine;
    int count = 0;
    for (const auto& [type, n] : reader.by_type) {
      mine += fmt::format("{}{} {}", mine.empty() ? "" : ", ", n, type);
      count += n;
    }
    sse_total += count;
    // Every step starts and completes once (no capture is repeated on a healthy station).
    const bool steps_seen = reader.by_type["step"] >= static_cast<int>(2 * record.steps.size());
    every_step_seen = every_step_seen && steps_seen;
    by_type += fmt::format(
        "\n  reader {}: {} messages ({}){}{}", r, count, mine,
        reader.saw_end ? "" : "; the run's completion NOT seen",
        steps_seen ? ""
                   : fmt::format("; fewer step messages than 2 x {} steps", record.steps.size()));
  }
  const double p50 = percentile(latencies_ms, 0.5);
  const double p95 = percentile(latencies_ms, 0.95);
  const double p99 = percentile(latencies_ms, 0.99);
  const double pmax = percentile(latencies_ms, 1.0);
  fmt::print(
      "{}: run {}: {} samples of {} IMUs at {} Hz ({:.0f} expected), {:.1f} s of station time "
      "in {:.1f} s wall; {} clients, {} status requests ({} failed)\n",
      through_drivers ? fmt::format("real drivers, time scale {}", time_scale)
                      : "simulated station",
      run, total, imus, rate_hz, expected_total, run_station_s, wall_s, clients,
      latencies_ms.size(), failures.load());
  fmt::print("SSE readers: {} messages{}\n", sse_total, by_type);
  fmt::print("GET {} latency [ms]: p50 {:.2f}  p95 {:.2f}  p99 {:.2f}  max {:.2f}\n", path, p50,
             p95, p99, pmax);
  if (writer_summary) {
    fmt::print("capture writer queue high-water: {} of {} samples ({:.2f} %)\n", writer_high_water,
               writer_capacity,
               100.0 * static_cast<double>(writer_high_water) /
                   static_cast<double>(std::max<std::uint64_t>(writer_capacity, 1)));
  } else {
    fmt::print("capture writer summary event: MISSING\n");
  }
  fmt::print(
      "dropped samples: {} (stored gaps {}, stored shortfall {}, stream gaps {}, writer refused "
      "{}); worst capture count error {:.0f} samples; {} captures repeated; {} fault events\n",
      dropped == 0 ? "none" : std::to_string(dropped), stored_gaps, stored_shortfall,
      stream_gap_samples, writer_refused, worst_count_error, repeated_captures, fault_events);
  const bool ok = dropped == 0 && repeated_captures == 0 && failures == 0 && all_saw_end() &&
                  every_step_seen && writer_summary;
  const nlohmann::json figures = {{"drivers", through_drivers},
                                  {"time_scale", time_scale},
                                  {"imus", imus},
                                  {"rate_hz", rate_hz},
                                  {"clients", clients},
                                  {"readers", readers},
                                  {"capture_s", capture_s},
                                  {"station_s", run_station_s},
                                  {"wall_s", wall_s},
                                  {"samples", total},
                                  {"expected", expected_total},
                                  {"dropped", dropped},
                                  {"repeated_captures", repeated_captures},
                                  {"requests", latencies_ms.size()},
                                  {"failed", failures.load()},
                                  {"p50_ms", p50},
                                  {"p95_ms", p95},
                                  {"p99_ms", p99},
                                  {"max_ms", pmax},
                                  {"writer_high_water", writer_high_water},
                                  {"writer_capacity", writer_capacity},
                                  {"sse_messages", sse_total},
                                  {"ok", ok}};
  fmt::print("{}\n", figures.dump());
  std::filesystem::remove_all(dir);
  return ok ? 0 : 1;
}

// POST /runs/{id}/fits on a long run against `calstand fit --json` on the same run (issue 14:
// "a fit from the console returns in about the time the CLI takes"): the same library call
// behind both, so the difference is the HTTP round trip against the process start. Plain
// program (prints figures), not a Google Benchmark: the run is recorded once, then each way is
// timed a few times.
// clang-format off
#include <Eigen/Core>  // before httplib.h: its <resolv.h> defines a macro `_res`, a name Eigen uses
#include <httplib.h>
// clang-format on
#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "analysis/fit_request.hpp"
#include "analysis/run_model.hpp"
#include "daemon/api/api_server.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/run_service.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"

namespace {

using namespace calstand;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string run_cli(const std::string& args) {
  FILE* pipe = popen((std::string(CALSTAND_BIN) + " " + args + " 2>/dev/null").c_str(), "r");
  if (!pipe) return "";
  std::string out;
  char buf[4096];
  while (std::size_t n = fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
  pclose(pipe);
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  // Six positions of `capture_s` each at the station's IMU rate (the default station: 200 Hz).
  const int capture_s = argc > 1 ? std::atoi(argv[1]) : 600;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 5;
  const auto dir = std::filesystem::temp_directory_path() /
                   ("calstand-analysis-bench-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string db = (dir / "bench.db").string();

  daemon::service::EventHub hub(4096);
  daemon::service::RunService service(
      {sim::load_station_or_default(""), db, daemon::service::RecoveryPolicy::kAuto}, hub);
  daemon::api::ApiOptions options;
  options.port = 0;
  daemon::api::ApiServer server(service, hub, options);
  const int port = server.start();
  service.start();
  httplib::Client client("127.0.0.1", port);
  client.set_read_timeout(600, 0);

  const auto t_record = Clock::now();
  const auto submitted = client.Post(
      "/runs",
      nlohmann::json{{"procedure", "six-position"}, {"parameters", {{"capture_s", capture_s}}}}
          .dump(),
      "application/json");
  if (!submitted || submitted->status != 201) {
    fmt::print(stderr, "submit refused\n");
    return 1;
  }
  const std::int64_t run = nlohmann::json::parse(submitted->body).at("id");
  for (;;) {
    const auto r = client.Get(fmt::format("/runs/{}", run));
    if (r && nlohmann::json::parse(r->body).value("status", "") == "completed") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::int64_t samples = 0;
  {
    const auto r = client.Get(fmt::format("/runs/{}/series?signal=gz&max_points=2", run));
    samples = nlohmann::json::parse(r->body).at("samples");
  }
  fmt::print("run {}: six-position, {} s captures, {} samples, recorded in {:.1f} s\n", run,
             capture_s, samples, seconds_since(t_record));

  std::vector<double> api, cli, library, series;
  for (int i = 0; i < repeats; ++i) {
    auto t0 = Clock::now();
    const auto r = client.Post(fmt::format("/runs/{}/fits", run), "{}", "application/json");
    api.push_back(seconds_since(t0));
    if (!r || r->status != 200) {
      fmt::print(stderr, "POST /fits failed\n");
      return 1;
    }
    t0 = Clock::now();
    const std::string out = run_cli(fmt::format("fit --db {} --run {} --json", db, run));
    cli.push_back(seconds_since(t0));
    if (out.empty()) {
      fmt::print(stderr, "calstand fit failed\n");
      return 1;
    }
    t0 = Clock::now();
    {
      store::Database d(db);
      analysis::FitRequest request;
      request.model = analysis::model_from_lists({}, {});
      analysis::fit_request(d, run, request);
    }
    library.push_back(seconds_since(t0));
    t0 = Clock::now();
    client.Get(fmt::format("/runs/{}/series?signal=gz&max_points=2000", run));
    series.push_back(seconds_since(t0));
  }
  fmt::print(
      "median of {}: POST /runs/{{id}}/fits {:.3f} s, calstand fit --json {:.3f} s, "
      "analysis::fit_request in process {:.3f} s; GET /series (2000 points) {:.3f} s\n",
      repeats, median(api), median(cli), median(library), median(series));
  service.stop("bench over");
  server.stop();
  std::filesystem::remove_all(dir);
  return 0;
}

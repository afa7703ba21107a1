// `calstand watch RUN`: follows a run on calstandd live (the daemon's server-sent events) with
// the progress bar of `calstand run`, printing step ends, faults and operator actions; exits
// when the run ends (0 when completed, 1 otherwise).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <thread>

#include "commands.hpp"
#include "core/error.hpp"
#include "daemon/run_state.hpp"
#include "daemon_client.hpp"
#include "progress_bar.hpp"

namespace calstand::cli {
namespace {

struct WatchOptions {
  DaemonAddress address;
  std::int64_t run = 0;
  double reconnect_s = 60.0;  ///< how long a lost stream is retried
};

// The bar's progress from GET /runs/RUN.
daemon::Progress progress_of(const nlohmann::json& r) {
  daemon::Progress p;
  p.steps = r["steps_total"].get<std::size_t>();
  if (r["current_step"].is_object()) {
    p.step = r["current_step"]["index"].get<std::size_t>();
    p.label = r["current_step"]["label"].get<std::string>();
  }
  if (r.contains("live")) {
    p.state = daemon::run_state_named(r["live"]["state"].get<std::string>())
                  .value_or(daemon::RunState::kIdle);
    p.phase = r["live"]["phase"].get<std::string>();
    p.eta_s = r["live"]["eta_s"].get<double>();
    p.station_time_s = r["live"]["station_time_s"].get<double>();
  } else {
    p.phase = r["status"].get<std::string>();
  }
  return p;
}

int watch(const WatchOptions& opt) {
  const DaemonClient client(opt.address);
  const std::string path = fmt::format("/runs/{}", opt.run);
  // A daemon away when the watch starts (restarting under its supervisor) is waited for as a
  // lost stream is, up to --reconnect; a refusal (4xx) is an error at once.
  const auto give_up = std::chrono::steady_clock::now() +
                       std::chrono::duration<double>(std::max(0.0, opt.reconnect_s));
  nlohmann::json status;
  for (;;) {
    try {
      status = client.get(path);
      break;
    } catch (const core::InputError&) {
      throw;
    } catch (const std::runtime_error&) {
      if (std::chrono::steady_clock::now() >= give_up) throw;
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
    }
  }
  ProgressBar bar;
  std::string final_state = status["status"];
  if (!daemon::has_ended(final_state)) {
    bar.update(progress_of(status));
    // A daemon restart (kill -9 and a supervisor bringing it back) is ridden out: the stream
    // reconnects and the run's own status says where it is.
    // The run's status for a redraw; none when the daemon went away in between (the stream then
    // breaks too, and reconnects). A refusal (4xx) is an error as ever.
    auto current = [&]() -> std::optional<nlohmann::json> {
      try {
        return client.get(path);
      } catch (const core::InputError&) {
        throw;
      } catch (const std::runtime_error&) {
        return std::nullopt;
      }
    };
    client.stream_events(opt.reconnect_s, [&](const std::string& type, const nlohmann::json& data) {
      if (type == "station" || type == "gap") {
        // The stream is (again) open, or messages were lost: the run may have ended meanwhile.
        const auto now = current();
        if (now && daemon::has_ended((*now)["status"].get<std::string>())) {
          final_state = (*now)["status"];
          return false;
        }
        if (now) bar.update(progress_of(*now));
        return true;
      }
      // Messages of other runs, and of the station between runs ("run": null), are not ours.
      const bool ours = data.is_object() && data.contains("run") &&
                        data["run"].is_number_integer() &&
                        data["run"].get<std::int64_t>() == opt.run;
      if (!ours) return true;
      if (type == "fault" || (type == "event" && data.value("kind", "") == "operator")) {
        bar.finish();
        fmt::print("{}: {}: {}\n", type, data.value("source", ""), data.value("message", ""));
      }
      if (type == "run" && daemon::has_ended(data.value("state", ""))) {
        final_state = data["state"];
        return false;
      }
      // Step changes and telemetry (about 2 Hz) pace the redraws.
      if (const auto now = current()) bar.update(progress_of(*now));
      return true;
    });
  }
  bar.finish();
  status = client.get(path);
  int skipped = 0;
  for (const auto& step : client.get(path + "/steps"))
    skipped += step.value("status", "") == "skipped";
  fmt::print("run {} {}: {}/{} steps{}{}\n", opt.run, status["status"].get<std::string>(),
             status["steps_done"].get<int>(), status["steps_total"].get<int>(),
             skipped > 0 ? fmt::format(", {} skipped", skipped) : "",
             status["exit_reason"].get<std::string>().empty()
                 ? ""
                 : " (" + status["exit_reason"].get<std::string>() + ")");
  return status["status"] == "completed" ? 0 : 1;
}

}  // namespace

void register_client_watch(CLI::App& app) {
  auto opt = std::make_shared<WatchOptions>();
  CLI::App* cmd =
      app.add_subcommand("watch", "Follow a run on calstandd live, with a progress bar");
  add_daemon_options(*cmd, opt->address);
  cmd->add_option("run", opt->run, "Run id")->required();
  cmd->add_option("--reconnect", opt->reconnect_s, "Seconds to keep reopening a lost stream")
      ->capture_default_str();
  cmd->callback([opt] {
    if (const int code = watch(*opt); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace calstand::cli

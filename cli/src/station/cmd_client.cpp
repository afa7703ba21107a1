// Client commands of calstandd: `submit`, `status`, `pause`, `resume`, `abort`, `skip` (and
// `watch`, in cmd_client_watch.cpp). They talk to the daemon's control API; nothing runs here.
#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>

#include "commands.hpp"
#include "core/error.hpp"
#include "daemon_client.hpp"
#include "procedures/library.hpp"
#include "procedures/procedure.hpp"
#include "progress_bar.hpp"
#include "unit_option.hpp"

namespace calstand::cli {
namespace {

struct ClientOptions {
  DaemonAddress address;
  std::string procedure;
  std::vector<std::string> set_args;
  std::vector<std::string> unit_args;  ///< submit: NAME=SERIAL
  std::int64_t run = 0;
  bool json = false;
  bool now = false;
  std::string reason = "operator request";
  std::optional<std::size_t> step;  ///< skip: the step meant (refused when the run is elsewhere)
};

// A library name goes by name; a file is read here and sent inline (the daemon never reads
// files a client names).
nlohmann::json procedure_field(const std::string& name_or_path) {
  if (procedures::library_text(name_or_path)) return name_or_path;
  std::ifstream in(name_or_path);
  if (!in) throw core::InputError(name_or_path, "neither a library procedure nor a readable file");
  std::stringstream text;
  text << in.rdbuf();
  try {
    return nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::parse_error& e) {
    throw core::InputError(name_or_path, std::string("not JSON: ") + e.what());
  }
}

int submit(const ClientOptions& opt) {
  nlohmann::json parameters = nlohmann::json::object();
  for (const auto& [k, v] : procedures::parse_overrides(opt.set_args)) parameters[k] = v;
  nlohmann::json body = {{"procedure", procedure_field(opt.procedure)}, {"parameters", parameters}};
  if (!opt.unit_args.empty()) body["units"] = parse_unit_options(opt.unit_args);
  const auto reply = DaemonClient(opt.address).post("/runs", body);
  if (opt.json) {
    fmt::print("{}\n", reply.dump());
  } else {
    fmt::print("run {} queued\n", reply.at("id").get<std::int64_t>());
  }
  return 0;
}

void print_run(const nlohmann::json& r) {
  fmt::print("run {} {}: {} ({}/{} steps)", r["id"].get<std::int64_t>(),
             r["procedure"].get<std::string>(), r["status"].get<std::string>(),
             r["steps_done"].get<int>(), r["steps_total"].get<int>());
  if (r.contains("live")) {
    fmt::print(", {} at step {} \"{}\", ETA {}", r["live"]["phase"].get<std::string>(),
               r["current_step"]["index"].get<int>() + 1,
               r["current_step"]["label"].get<std::string>(),
               format_duration(r["eta_s"].get<double>()));
  }
  if (!r["exit_reason"].get<std::string>().empty())
    fmt::print(" ({})", r["exit_reason"].get<std::string>());
  fmt::print("\n");
}

int client_status(const ClientOptions& opt) {
  const DaemonClient client(opt.address);
  if (opt.run > 0) {
    const auto r = client.get(fmt::format("/runs/{}", opt.run));
    if (opt.json) {
      fmt::print("{}\n", r.dump(2));
    } else {
      print_run(r);
    }
    return 0;
  }
  const auto station = client.get("/station");
  if (opt.json) {
    fmt::print("{}\n", station.dump(2));
    return 0;
  }
  fmt::print("station {}\n", station["name"].get<std::string>());
  for (const auto& d : station["devices"]) {
    std::string faults;
    for (const auto& [name, count] : d["fault_counters"].items()) {
      if (count.get<std::uint64_t>() > 0)
        faults += fmt::format(" {}={}", name, count.get<std::uint64_t>());
    }
    fmt::print("  {:<8} {:<10} {:<8} {}{}\n", d["kind"].get<std::string>(),
               d["name"].get<std::string>(), d["backend"].get<std::string>(),
               d["state"].get<std::string>(), faults);
  }
  if (!station["run"].is_null())
    print_run(client.get(fmt::format("/runs/{}", station["run"].get<std::int64_t>())));
  if (!station["held"].is_null()) {
    fmt::print("run {} is held after an interruption: calstand resume {} or calstand abort {}\n",
               station["held"].get<std::int64_t>(), station["held"].get<std::int64_t>(),
               station["held"].get<std::int64_t>());
  }
  for (const auto& q : station["queue"]) {
    fmt::print("queued: run {} (by {} at {})\n", q["run"].get<std::int64_t>(),
               q["submitted_by"].get<std::string>(), q["submitted_utc"].get<std::string>());
  }
  if (station.contains("waiting") && station["waiting"].is_string()) {
    fmt::print("waiting: {}\n", station["waiting"].get<std::string>());
  }
  if (station["run"].is_null() && station["queue"].empty() && station["held"].is_null())
    fmt::print("idle\n");
  return 0;
}

int action(const ClientOptions& opt, const std::string& verb) {
  nlohmann::json body = nlohmann::json::object();
  if (verb == "pause") body["immediate"] = opt.now;
  if (verb == "abort" || verb == "skip") body["reason"] = opt.reason;
  if (verb == "skip" && opt.step) body["step"] = *opt.step;
  const auto reply =
      DaemonClient(opt.address).post(fmt::format("/runs/{}/{}", opt.run, verb), body);
  fmt::print("run {}: {} requested\n", opt.run, reply.value("requested", verb));
  return 0;
}

CLI::App* add_client_command(CLI::App& app, const std::string& name, const std::string& help,
                             const std::shared_ptr<ClientOptions>& opt) {
  CLI::App* cmd = app.add_subcommand(name, help);
  add_daemon_options(*cmd, opt->address);
  return cmd;
}

}  // namespace

void register_client(CLI::App& app) {
  auto opt = std::make_shared<ClientOptions>();
  CLI::App* submit_cmd = add_client_command(app, "submit", "Queue a procedure on calstandd", opt);
  submit_cmd->add_option("procedure", opt->procedure, "Library name or procedure file")->required();
  submit_cmd->add_option("--set", opt->set_args, "Override a parameter: NAME=VALUE (JSON)");
  submit_cmd->add_option("--unit", opt->unit_args, "The unit in an IMU slot: NAME=SERIAL");
  submit_cmd->add_flag("--json", opt->json, "Print {\"id\": RUN}");
  submit_cmd->callback([opt] { submit(*opt); });

  CLI::App* status_cmd =
      add_client_command(app, "status", "The daemon's station, run and queue, or one run", opt);
  status_cmd->add_option("run", opt->run, "Run id (default: the whole station)");
  status_cmd->add_flag("--json", opt->json, "JSON as the API gives it");
  status_cmd->callback([opt] { client_status(*opt); });

  CLI::App* pause_cmd = add_client_command(app, "pause", "Pause a run on calstandd", opt);
  pause_cmd->add_option("run", opt->run, "Run id")->required();
  pause_cmd->add_flag("--now", opt->now, "At once (the capture in progress is repeated on resume)");
  pause_cmd->callback([opt] { action(*opt, "pause"); });

  CLI::App* resume_cmd =
      add_client_command(app, "resume", "Resume a paused or held run on calstandd", opt);
  resume_cmd->add_option("run", opt->run, "Run id")->required();
  resume_cmd->callback([opt] { action(*opt, "resume"); });

  CLI::App* abort_cmd =
      add_client_command(app, "abort", "Abort a run on calstandd (station to safe state)", opt);
  abort_cmd->add_option("run", opt->run, "Run id")->required();
  abort_cmd->add_option("--reason", opt->reason, "Why (recorded)")->capture_default_str();
  abort_cmd->callback([opt] { action(*opt, "abort"); });

  CLI::App* skip_cmd = add_client_command(
      app, "skip", "Skip the step in progress of a run on calstandd (or the next one while paused)",
      opt);
  skip_cmd->add_option("run", opt->run, "Run id")->required();
  skip_cmd->add_option("--step", opt->step, "The step meant: refused when the run is at another");
  skip_cmd->add_option("--reason", opt->reason, "Why (recorded)")->capture_default_str();
  skip_cmd->callback([opt] { action(*opt, "skip"); });
}

}  // namespace calstand::cli

// calstandd: the station daemon. Owns the station, runs the queue of runs in its database one
// at a time, serves the control API (schemas/api.md), and after a crash resumes or holds the
// interrupted run (--recovery). SIGTERM/SIGINT: the run in progress is checkpointed (the
// station made safe, the run set back to 'interrupted'), then the daemon exits 0. Under
// systemd (Type=notify): READY=1 once it serves, STATUS= lines, STOPPING=1, the watchdog fed
// by the run thread, and the log in the journal (docs/packaging.md).
#include <fmt/format.h>
#include <pthread.h>
#include <spdlog/sinks/rotating_file_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "core/version.hpp"
#include "daemon/api/api_server.hpp"
#include "daemon/api/tokens_file.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/fleet_publisher.hpp"
#include "daemon/service/journal_sink.hpp"
#include "daemon/service/run_service.hpp"
#include "daemon/service/service_heartbeat.hpp"
#include "daemon/service/systemd_notify.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"
#include "store/database_lock.hpp"
#include "store/upgrade.hpp"
#include "wire/listen_address.hpp"

namespace {

using calstand::core::InputError;

struct Options {
  std::string station_file;
  std::string db;
  std::string listen = "127.0.0.1:8765";
  std::string token_file;
  std::string tokens_file;
  std::string tls_cert;
  std::string tls_key;
  bool allow_plaintext = false;
  std::string log_dir;
  std::string recovery = "auto";
  std::string log_level = "info";
  std::string publish;  ///< the fleet's central database (postgresql://...), or none
  std::string publish_password_file;
  std::string publish_name;
  double publish_interval_s = 300.0;
  bool publish_samples = false;
  std::string fleet;  ///< the central database shown read-only under /fleet, or none
  std::string fleet_password_file;
  int request_deadline_s = 30;
  int max_connections_per_address = 16;
};

// A secret anyone on the machine can read is no secret; warned rather than refused, since a
// group-readable file can be meant (a service group).
void warn_if_others_read(const std::string& file) {
  struct stat st {};
  if (::stat(file.c_str(), &st) == 0 && (st.st_mode & 077) != 0) {
    spdlog::warn("{}: readable by others than its owner (chmod 600)", file);
  }
}

std::string read_token(const Options& opt) {
  if (opt.token_file.empty()) {
    const char* env = std::getenv("CALSTAND_TOKEN");
    return env ? env : "";
  }
  std::ifstream in(opt.token_file);
  if (!in) throw InputError(opt.token_file, "cannot read the token file");
  std::string token;
  std::getline(in, token);
  while (!token.empty() && std::isspace(static_cast<unsigned char>(token.back()))) token.pop_back();
  if (token.size() < 16)
    throw InputError(opt.token_file, "the token must have at least 16 characters");
  warn_if_others_read(opt.token_file);
  return token;
}

void set_up_logging(const Options& opt) {
  namespace svc = calstand::daemon::service;
  std::vector<spdlog::sink_ptr> sinks;
  // Under systemd the lines go to the journal with their fields (RUN, STEP, DEVICE), not as
  // plain text through stderr; elsewhere to stderr (and the files of --log-dir).
  if (svc::stderr_is_journal()) {
    try {
      sinks.push_back(std::make_shared<svc::JournalSink>("calstandd"));
    } catch (const std::exception& e) {
      std::cerr << "calstandd: journal unavailable (" << e.what() << "): logging to stderr\n";
    }
  }
  if (sinks.empty()) sinks.push_back(std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
  if (!opt.log_dir.empty()) {
    std::filesystem::create_directories(opt.log_dir);
    // 10 MB per file, 5 files: weeks of a busy station's log.
    sinks.push_back(std::make_shared<spdlog::sinks::rotating_file_sink_mt>(
        (std::filesystem::path(opt.log_dir) / "calstandd.log").string(), 10 * 1024 * 1024, 5));
  }
  auto logger = std::make_shared<spdlog::logger>("calstandd", sinks.begin(), sinks.end());
  logger->set_level(spdlog::level::from_str(opt.log_level));
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
}

int run_daemon(const Options& opt, const sigset_t& stop_signals) {
  namespace svc = calstand::daemon::service;
  // Read (and taken out of the environment) before any thread or child process starts.
  const svc::SystemdNotifier notifier = svc::SystemdNotifier::from_environment();
  set_up_logging(opt);
  namespace api = calstand::daemon::api;
  svc::ServiceOptions service_options;
  service_options.station = calstand::sim::load_station_or_default(opt.station_file);
  service_options.db_path = opt.db;
  service_options.recovery = svc::parse_recovery_policy(opt.recovery, "--recovery");
  api::ApiOptions api_options;
  std::tie(api_options.host, api_options.port) = calstand::wire::parse_listen_address(opt.listen);
  api_options.token = read_token(opt);
  // Plain-text secrets keep working, with a word on how to stop keeping them (docs/security.md).
  if (!api_options.token.empty()) {
    spdlog::warn(
        "{}: the operator token is kept in plain text; prefer a hashed one: calstand token add "
        "NAME --role operator --file FILE, then calstandd --tokens FILE",
        opt.token_file.empty() ? std::string("CALSTAND_TOKEN") : opt.token_file);
  }
  if (!opt.tokens_file.empty()) {
    api_options.tokens = api::load_tokens_file(opt.tokens_file);
    warn_if_others_read(opt.tokens_file);
    for (const api::NamedToken& t : api_options.tokens) {
      if (t.hashed()) continue;
      spdlog::warn(
          "{}: token '{}' is kept in plain text; replace it with a hashed one: calstand token "
          "remove {} --file {}, then calstand token add {} --role {} --file {}",
          opt.tokens_file, t.name, t.name, opt.tokens_file, t.name, api::to_string(t.role),
          opt.tokens_file);
    }
  }
  api_options.tls_cert_file = opt.tls_cert;
  api_options.tls_key_file = opt.tls_key;
  api_options.allow_plaintext = opt.allow_plaintext;
  api_options.request_deadline_s = opt.request_deadline_s;
  api_options.max_connections_per_address = opt.max_connections_per_address;
  if (!opt.fleet.empty()) {
    api_options.fleet =
        calstand::fleet::parse_central_address(opt.fleet, opt.fleet_password_file, "--fleet");
  }
  // Before anything is opened: refuses an open port without a token, or without TLS.
  api_options.validate();
  if (api_options.allow_plaintext && !api_options.uses_tls() &&
      !calstand::daemon::api::is_loopback_address(api_options.host)) {
    spdlog::warn(
        "{}: plaintext beyond loopback (--allow-plaintext): tokens and data cross the "
        "network readable by anyone on it",
        opt.listen);
  }
  svc::PublisherOptions publisher_options;
  if (!opt.publish.empty()) {
    // Checked before anything is opened, as the API options: a password in the URL is refused.
    publisher_options.central =
        calstand::fleet::parse_central_address(opt.publish, opt.publish_password_file, "--publish");
    publisher_options.db_path = opt.db;
    publisher_options.sync.station_name =
        opt.publish_name.empty() ? service_options.station.name : opt.publish_name;
    publisher_options.sync.samples = opt.publish_samples;
    publisher_options.interval_s = opt.publish_interval_s;
    publisher_options.max_retry_s = std::max(600.0, opt.publish_interval_s);
    publisher_options.validate();
  }
  // This daemon alone drives the database's station (released by the kernel if it dies).
  const calstand::store::DatabaseLock owner(
      opt.db, calstand::store::DatabaseLock::Mode::kExclusive,
      fmt::format("calstandd pid {} listening on {}", ::getpid(), opt.listen));
  // Opens (and migrates) once, or fails here: an older schema is backed up first, a newer one
  // (a downgrade) refused by name.
  const auto upgrade = calstand::store::upgrade_database(opt.db, [&](int from, int to) {
    spdlog::info(
        "database {}: schema {} is older than this calstandd's {}: backing it up, then "
        "migrating",
        opt.db, from, to);
    notifier.notify(
        fmt::format("STATUS=database: backing up schema {} before migrating to {}", from, to));
  });
  if (!upgrade.backup.empty()) {
    spdlog::info("database {}: migrated from schema {} to {}; the copy as it was: {}", opt.db,
                 upgrade.from_version, upgrade.to_version, upgrade.backup);
  }

  svc::EventHub hub;
  svc::RunService service(service_options, hub);
  // Made before the API (it does no I/O until started), so that GET /station/publish reads it.
  std::unique_ptr<svc::FleetPublisher> publisher;
  if (!opt.publish.empty()) {
    publisher = std::make_unique<svc::FleetPublisher>(publisher_options, hub);
    api_options.publish_status = [&publisher] { return publisher->status(); };
  }
  // systemd's watchdog and status, fed by the run thread (ServiceHeartbeat).
  // Owned by the run thread's callback: it lives as long as the thread can call it.
  auto heartbeat =
      std::make_shared<svc::ServiceHeartbeat>(notifier, [&service] { return service.snapshot(); });
  if (notifier.enabled()) {
    std::chrono::milliseconds period(1000);
    if (const auto w = notifier.watchdog()) {
      period = std::min(period, std::chrono::duration_cast<std::chrono::milliseconds>(*w / 4));
      spdlog::info("systemd watchdog: {} s; the run thread pings it",
                   std::chrono::duration<double>(*w).count());
    }
    service.set_heartbeat([heartbeat] { heartbeat->beat(); },
                          std::max(period, std::chrono::milliseconds(10)));
  }
  api::ApiServer server(service, hub, api_options);
  const int port = server.start();
  // One line on stdout that scripts and tests read (the port when --listen asked for 0).
  fmt::print("calstandd: listening on {}://{}:{}\n", server.uses_tls() ? "https" : "http",
             api_options.host, port);
  std::fflush(stdout);
  spdlog::info("station {} ({} IMUs), database {}, recovery {}", service_options.station.name,
               service_options.station.imus.size(), opt.db, opt.recovery);
  service.start();
  // Serving now: systemd may start what comes after calstandd.service.
  notifier.notify(fmt::format("READY=1\nSTATUS={}", svc::status_line(service.snapshot())));
  if (publisher) {
    publisher->start();
    spdlog::info("publishing to {} every {} s and when a run ends{}",
                 publisher_options.central.display, opt.publish_interval_s,
                 opt.publish_samples ? ", samples included" : "");
  }

  int sig = 0;
  sigwait(&stop_signals, &sig);
  const std::string why = sig == SIGTERM ? "SIGTERM" : sig == SIGINT ? "SIGINT" : "SIGHUP";
  spdlog::info("{} received: checkpointing the run in progress and stopping", why);
  notifier.notify("STOPPING=1\nSTATUS=stopping: checkpointing the run in progress (" + why + ")");
  service.stop(why);
  if (publisher) publisher->stop();
  server.stop();
  spdlog::info("stopped cleanly");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // The stop signals are taken by sigwait() in main: blocked before any thread starts, so
  // every thread inherits the mask and none is interrupted by them.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  for (int s : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&stop_signals, s);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  std::signal(SIGPIPE, SIG_IGN);  // a client that goes away must not kill the daemon

  CLI::App app{"calstandd: the calstand station daemon (queue, control API, crash recovery)"};
  Options opt;
  app.add_option("--station", opt.station_file, "Station file (default: built-in simulator)");
  app.add_option("--db", opt.db, "SQLite database (runs, queue, samples)")->required();
  app.add_option("--listen", opt.listen, "Address and port of the control API")
      ->capture_default_str();
  app.add_option("--token-file", opt.token_file,
                 "File holding one operator token, named 'operator' (else env CALSTAND_TOKEN)");
  app.add_option("--tokens", opt.tokens_file,
                 "Named tokens with their role, read or operator (schemas/tokens.schema.json)");
  app.add_option("--tls-cert", opt.tls_cert, "TLS certificate chain (PEM): serve https");
  app.add_option("--tls-key", opt.tls_key, "Private key of --tls-cert (PEM)");
  app.add_flag("--allow-plaintext", opt.allow_plaintext,
               "Serve plain http beyond loopback (a network you trust; else TLS is required)");
  app.add_option("--request-deadline-s", opt.request_deadline_s,
                 "A request (line, headers, body) must arrive within this from its first byte [s]")
      ->capture_default_str();
  app.add_option("--max-connections-per-address", opt.max_connections_per_address,
                 "Connections one client address may hold at once; more get 503")
      ->capture_default_str();
  app.add_option("--log-dir", opt.log_dir, "Directory of the rotating log file calstandd.log");
  app.add_option("--recovery", opt.recovery, "Interrupted run on start: auto (resume) or hold")
      ->capture_default_str();
  app.add_option("--log-level", opt.log_level, "trace, debug, info, warn, error")
      ->capture_default_str();
  app.add_option("--publish", opt.publish,
                 "Copy ended runs, records, verdicts and fits to the fleet's central database "
                 "(postgresql://USER@HOST/DB, no password) in the background");
  app.add_option("--publish-password-file", opt.publish_password_file,
                 "Password file of --publish (libpq's .pgpass format, mode 600)");
  app.add_option("--publish-name", opt.publish_name,
                 "Name the station registers with (default: the station file's name)");
  app.add_option("--publish-interval-s", opt.publish_interval_s,
                 "Seconds between publish passes (and a pass when a run ends)")
      ->capture_default_str();
  app.add_flag("--publish-samples", opt.publish_samples, "Publish the sample chunks too");
  app.add_option("--fleet", opt.fleet,
                 "Show the fleet's central database read-only under /fleet and in the console "
                 "(postgresql://READER@HOST/DB, no password)");
  app.add_option("--fleet-password-file", opt.fleet_password_file,
                 "Password file of --fleet (libpq's .pgpass format, mode 600)");
  app.set_version_flag("--version", std::string("calstandd ") + calstand::core::kVersion);
  try {
    app.parse(argc, argv);
    return run_daemon(opt, stop_signals);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const InputError& e) {
    std::cerr << "calstandd: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "calstandd: error: " << e.what() << "\n";
    return 1;
  }
}

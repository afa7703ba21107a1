// Kill -9 soak (issue 16): a whole `thermal-calibration` is killed with SIGKILL at N points
// spread over its steps (soaks, moves, rate steps, captures, the final return to 25 degC), each
// time in a fresh database, and resumed to completion; every resumed run is compared with an
// uninterrupted one: the same steps, all completed, the same per-step sample counts (to one
// sample), no duplicate or missing sequence number in any step, PRAGMA integrity_check ok.
//
//   --mode cli     the foreground `calstand run`, killed, then `calstand run --resume 1`
//   --mode daemon  calstandd running the submitted run, killed, then started again: it resumes
//                  the run by itself (recovery auto)
//
//   calstand_kill_soak [--mode cli|daemon|both] [--points N] [--work DIR] [--seed S]
//                      [--full]  (the library's default parameters: hours of station time,
//                                 minutes of CPU per run; default: a reduced campaign)
//
// One line per kill point, then a JSON line per mode: {"mode", "points", "passed", "failed",
// "killed_in": {kind: count}}. Exit 0 when every point passed.
// clang-format off
#include <Eigen/Core>  // before httplib.h: its <resolv.h> defines a macro `_res`, a name Eigen uses
#include <httplib.h>
// clang-format on
#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "store/database.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"

namespace {

namespace fs = std::filesystem;
using namespace calstand;
using Clock = std::chrono::steady_clock;

// The reduced campaign of tests/integration/campaign_test.cpp: two plateaus, six orientations,
// two rates, short captures (the same parameters as --set arguments and as a JSON object).
const nlohmann::json kReduced = {{"temperatures", {15, 35}}, {"soak_s", 600},
                                 {"capture_s", 4},           {"outer_angles", {0, 90, 180}},
                                 {"inner_angles", {0, 90}},  {"rates", {20, 90}},
                                 {"revolutions", 1},         {"ramp_c_per_min", 2}};

struct Options {
  std::string mode = "both";
  int points = 20;
  std::string work = (fs::temp_directory_path() / "calstand-kill-soak").string();
  unsigned seed = 1;
  bool full = false;
};

std::string set_args(const nlohmann::json& params) {
  std::string out;
  for (const auto& [k, v] : params.items()) out += fmt::format(" --set '{}={}'", k, v.dump());
  return out;
}

pid_t spawn(const std::vector<std::string>& argv, const std::string& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    dup2(fd, STDOUT_FILENO);
    dup2(fd, STDERR_FILENO);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

int wait_exit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

// A read-only look at the run's steps while another process writes them.
struct StepState {
  int running = -1;    ///< index of the step marked running, -1 when none
  int completed = 0;   ///< steps completed
  std::string kind;    ///< of the running step
  std::string status;  ///< of the run
};
std::optional<StepState> peek(const std::string& db) {
  if (!fs::exists(db)) return std::nullopt;
  sqlite3* h = nullptr;
  if (sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    sqlite3_close(h);
    return std::nullopt;
  }
  sqlite3_busy_timeout(h, 200);
  StepState out;
  bool ok = true;
  auto each = [&](const char* sql, auto&& row) {
    sqlite3_stmt* st = nullptr;
    if (sqlite3_prepare_v2(h, sql, -1, &st, nullptr) != SQLITE_OK) {
      ok = false;
      return;
    }
    while (sqlite3_step(st) == SQLITE_ROW) row(st);
    sqlite3_finalize(st);
  };
  each("SELECT idx, kind, status FROM steps WHERE run_id = 1", [&](sqlite3_stmt* st) {
    const std::string status = reinterpret_cast<const char*>(sqlite3_column_text(st, 2));
    if (status == "completed") ++out.completed;
    if (status == "running") {
      out.running = sqlite3_column_int(st, 0);
      out.kind = reinterpret_cast<const char*>(sqlite3_column_text(st, 1));
    }
  });
  each("SELECT status FROM runs WHERE id = 1", [&](sqlite3_stmt* st) {
    out.status = reinterpret_cast<const char*>(sqlite3_column_text(st, 0));
  });
  sqlite3_close(h);
  if (!ok) return std::nullopt;
  return out;
}

struct StepData {
  std::string label, status;
  std::size_t samples = 0;
};

// Every step of run 1 with its status and sample count; `problems` gets what is wrong.
std::vector<StepData> read_run(const std::string& db_file, std::vector<std::string>& problems) {
  store::Database db(db_file);
  std::vector<StepData> out;
  for (const auto& s : store::RunStore(db).load_run(1).steps) {
    StepData d{s.label, std::string(store::to_string(s.status)), 0};
    const auto samples = store::read_samples(db, 1, s.index, "imu0");
    d.samples = samples.size();
    for (std::size_t k = 1; k < samples.size(); ++k) {
      if (samples[k].sequence != (samples[k - 1].sequence + 1) % 65536) {
        problems.push_back(fmt::format("step {}: sequence {} after {}", s.index,
                                       samples[k].sequence, samples[k - 1].sequence));
        break;
      }
    }
    out.push_back(d);
  }
  SQLite::Statement q(db.sql(), "PRAGMA integrity_check");
  q.executeStep();
  if (q.getColumn(0).getString() != "ok") {
    problems.push_back("integrity_check: " + q.getColumn(0).getString());
  }
  return out;
}

std::vector<std::string> compare(const std::vector<StepData>& got,
                                 const std::vector<StepData>& reference) {
  std::vector<std::string> problems;
  if (got.size() != reference.size()) {
    problems.push_back(fmt::format("{} steps, reference {}", got.size(), reference.size()));
    return problems;
  }
  for (std::size_t i = 0; i < got.size(); ++i) {
    if (got[i].status != "completed") {
      problems.push_back(fmt::format("step {} ({}) {}", i, got[i].label, got[i].status));
    }
    const auto diff =
        static_cast<long long>(got[i].samples) - static_cast<long long>(reference[i].samples);
    if (diff < -1 || diff > 1) {
      problems.push_back(fmt::format("step {} ({}): {} samples, reference {}", i, got[i].label,
                                     got[i].samples, reference[i].samples));
    }
  }
  return problems;
}

class Soak {
 public:
  explicit Soak(Options opt) : opt_(std::move(opt)) {
    params_ = opt_.full ? nlohmann::json::object() : kReduced;
    fs::remove_all(opt_.work);
    fs::create_directories(opt_.work);
  }

  std::string calstand() const { return CALSTAND_BIN; }
  std::string calstandd() const { return CALSTANDD_BIN; }

  bool reference() {
    const std::string db = opt_.work + "/reference.db";
    const auto t0 = Clock::now();
    const int code = std::system((calstand() + " run thermal-calibration --quiet --db " + db +
                                  set_args(params_) + " > " + opt_.work + "/reference.log 2>&1")
                                     .c_str());
    reference_seconds_ = std::chrono::duration<double>(Clock::now() - t0).count();
    std::vector<std::string> problems;
    reference_ = read_run(db, problems);
    fmt::print("reference: {} steps in {:.1f} s (exit {})\n", reference_.size(), reference_seconds_,
               code);
    return code == 0 && problems.empty() && !reference_.empty();
  }

  // The kill points: steps spread evenly over the whole run, each with a delay into the step
  // (a fraction of the reference's mean step time) so kills land inside steps, not only at
  // their starts.
  std::vector<std::pair<int, double>> points() const {
    std::mt19937 rng(opt_.seed);
    std::uniform_real_distribution<double> frac(0.0, 1.0);
    const double mean_step_s = reference_seconds_ / static_cast<double>(reference_.size());
    std::vector<std::pair<int, double>> out;
    const int n = opt_.points;
    for (int k = 0; k < n; ++k) {
      const int step = static_cast<int>(
          std::lround(static_cast<double>(k) * static_cast<double>(reference_.size() - 1) /
                      static_cast<double>(std::max(1, n - 1))));
      out.emplace_back(step, frac(rng) * mean_step_s);
    }
    return out;
  }

  /// One kill point of `mode`; prints its line; true when it passed.
  bool point(const std::string& mode, int k, int step, double delay_s) {
    const std::string dir = fmt::format("{}/{}-{:02d}", opt_.work, mode, k);
    fs::create_directories(dir);
    const std::string db = dir + "/station.db";
    const std::string log = dir + "/log.txt";
    pid_t pid = -1;
    int port = 0;
    if (mode == "cli") {
      std::vector<std::string> argv{calstand(), "run",  "thermal-calibration",
                                    "--quiet",  "--db", db};
      for (const auto& [key, v] : params_.items()) {
        argv.push_back("--set");
        argv.push_back(key + "=" + v.dump());
      }
      pid = spawn(argv, log);
    } else {
      pid = start_daemon(db, log, port);
      if (pid < 0) return report(mode, k, step, "", {"calstandd did not start"});
      httplib::Client c("127.0.0.1", port);
      const auto r = c.Post(
          "/runs", {{"Authorization", "Bearer " + token()}},
          nlohmann::json{{"procedure", "thermal-calibration"}, {"parameters", params_}}.dump(),
          "application/json");
      if (!r || r->status != 201) {
        kill(pid, SIGKILL);
        wait_exit(pid);
        return report(mode, k, step, "", {"submit refused"});
      }
    }
    // Wait for the step to be under way, then for the delay into it, and kill.
    std::string killed_in;
    const auto deadline = Clock::now() + std::chrono::minutes(10);
    bool ended = false;
    while (Clock::now() < deadline) {
      const auto s = peek(db);
      if (s && (s->running > step || s->completed > step || s->status == "completed")) break;
      if (s && s->running == step) {
        std::this_thread::sleep_for(std::chrono::duration<double>(delay_s));
        break;
      }
      int status = 0;
      if (waitpid(pid, &status, WNOHANG) == pid) {
        ended = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (!ended) {
      kill(pid, SIGKILL);
      wait_exit(pid);
    }
    const auto at_kill = peek(db);
    killed_in = !at_kill                         ? "before the database"
                : at_kill->status == "completed" ? "after the run ended"
                : at_kill->running >= 0          ? at_kill->kind
                                                 : "between steps";
    // Resume to completion.
    std::vector<std::string> problems;
    if (mode == "cli") {
      const int code = std::system(
          (calstand() + " run --quiet --resume 1 --db " + db + " >> " + log + " 2>&1").c_str());
      if (code != 0 && (!at_kill || at_kill->status != "completed")) {
        problems.push_back(fmt::format("resume exited {}", code));
      }
    } else {
      pid = start_daemon(db, log, port);
      if (pid < 0) return report(mode, k, step, killed_in, {"calstandd did not restart"});
      const auto until = Clock::now() + std::chrono::minutes(10);
      std::string status;
      while (Clock::now() < until) {
        status = peek(db).value_or(StepState{}).status;
        if (status == "completed" || status == "failed" || status == "aborted") break;
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
      kill(pid, SIGTERM);
      wait_exit(pid);
      if (status != "completed") problems.push_back("run " + status + " after the restart");
    }
    auto got = read_run(db, problems);
    for (auto& p : compare(got, reference_)) problems.push_back(std::move(p));
    return report(mode, k, step, killed_in, problems);
  }

  bool report(const std::string& mode, int k, int step, const std::string& killed_in,
              const std::vector<std::string>& problems) {
    ++killed_in_[mode][killed_in.empty() ? "not killed" : killed_in];
    fmt::print("{:6} point {:2}: step {:3} ({}), killed in {}: {}\n", mode, k, step,
               reference_[static_cast<std::size_t>(step)].label, killed_in,
               problems.empty() ? "ok" : fmt::format("FAILED: {}", fmt::join(problems, "; ")));
    std::fflush(stdout);
    return problems.empty();
  }

  const Options& options() const { return opt_; }
  std::map<std::string, int> killed_in(const std::string& mode) { return killed_in_[mode]; }

 private:
  static std::string token() { return "kill-soak-token-0123456789"; }

  pid_t start_daemon(const std::string& db, const std::string& log, int& port) {
    int out[2];
    if (pipe(out) != 0) return -1;
    const pid_t pid = fork();
    if (pid == 0) {
      dup2(out[1], STDOUT_FILENO);
      const int err = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      dup2(err, STDERR_FILENO);
      close(out[0]);
      setenv("CALSTAND_TOKEN", token().c_str(), 1);
      const std::string bin = calstandd();
      execl(bin.c_str(), bin.c_str(), "--db", db.c_str(), "--listen", "127.0.0.1:0", nullptr);
      _exit(127);
    }
    close(out[1]);
    std::string line;
    char c = 0;
    while (read(out[0], &c, 1) == 1 && c != '\n') line += c;
    close(out[0]);
    const auto colon = line.rfind(':');
    if (line.find("listening on") == std::string::npos || colon == std::string::npos) {
      kill(pid, SIGKILL);
      wait_exit(pid);
      return -1;
    }
    port = std::atoi(line.c_str() + colon + 1);
    return pid;
  }

  Options opt_;
  nlohmann::json params_;
  std::vector<StepData> reference_;
  double reference_seconds_ = 0.0;
  std::map<std::string, std::map<std::string, int>> killed_in_;
};

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        fmt::print(stderr, "{} needs a value\n", a);
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--mode") {
      opt.mode = value();
    } else if (a == "--points") {
      opt.points = std::stoi(value());
    } else if (a == "--work") {
      opt.work = value();
    } else if (a == "--seed") {
      opt.seed = static_cast<unsigned>(std::stoul(value()));
    } else if (a == "--full") {
      opt.full = true;
    } else {
      fmt::print(stderr,
                 "usage: calstand_kill_soak [--mode cli|daemon|both] [--points N] [--work DIR] "
                 "[--seed S] [--full]\n");
      return 2;
    }
  }
  if (opt.mode != "cli" && opt.mode != "daemon" && opt.mode != "both") {
    fmt::print(stderr, "--mode: cli, daemon or both\n");
    return 2;
  }
  if (opt.points < 1) {
    fmt::print(stderr, "--points: at least 1\n");
    return 2;
  }
  Soak soak(opt);
  if (!soak.reference()) {
    fmt::print(stderr, "the uninterrupted reference run failed\n");
    return 1;
  }
  bool all = true;
  for (const std::string mode : {"cli", "daemon"}) {
    if (opt.mode != "both" && opt.mode != mode) continue;
    int passed = 0;
    std::vector<int> failed;
    const auto points = soak.points();
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (soak.point(mode, static_cast<int>(k), points[k].first, points[k].second)) {
        ++passed;
      } else {
        failed.push_back(static_cast<int>(k));
      }
    }
    all = all && failed.empty();
    fmt::print("{}\n", nlohmann::json{{"mode", mode},
                                      {"points", points.size()},
                                      {"passed", passed},
                                      {"failed", failed},
                                      {"killed_in", soak.killed_in(mode)}}
                           .dump());
  }
  return all ? 0 : 1;
}

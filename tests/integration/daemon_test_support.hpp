#pragma once
// Helpers of the calstandd tests: a JSON client for the control API, polling with a deadline,
// and a server-sent-events reader on its own thread.

// clang-format off
#include <Eigen/Core>  // before httplib.h: its <resolv.h> defines a macro `_res`, a name Eigen uses
#include <httplib.h>
// clang-format on
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "test_time.hpp"
#include "wire/sse_decoder.hpp"

namespace calstand::testing {

inline constexpr const char* kTestToken = "test-token-0123456789abcdef";

/// A fresh directory for one test's database.
inline std::string fresh_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("calstandd-test-" + std::to_string(::getpid()) + "-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

struct Reply {
  int status = 0;  ///< 0: no answer (connection failed)
  nlohmann::json body;
  std::string raw;
  httplib::Headers headers;
};

/// Requests against the API on 127.0.0.1:port; POSTs carry the token unless told otherwise.
class ApiClient {
 public:
  explicit ApiClient(int port) : port_(port) {}

  Reply get(const std::string& path) {
    httplib::Client c("127.0.0.1", port_);
    c.set_read_timeout(scaled(std::chrono::seconds(10)));
    return reply(c.Get(path.c_str()));
  }
  Reply post(const std::string& path, const std::string& body,
             const std::string& token = kTestToken) {
    httplib::Client c("127.0.0.1", port_);
    c.set_read_timeout(scaled(std::chrono::seconds(10)));
    httplib::Headers headers{{"X-Calstand-Operator", "tester"}};
    if (!token.empty()) headers.emplace("Authorization", "Bearer " + token);
    return reply(c.Post(path.c_str(), headers, body, "application/json"));
  }
  Reply post_json(const std::string& path, const nlohmann::json& body) {
    return post(path, body.dump());
  }

  /// POST /runs of a library procedure with parameters; the run id (0 when refused).
  std::int64_t submit(const std::string& procedure, const nlohmann::json& parameters) {
    const Reply r = post_json("/runs", {{"procedure", procedure}, {"parameters", parameters}});
    return r.status == 201 ? r.body.at("id").get<std::int64_t>() : 0;
  }

 private:
  static Reply reply(const httplib::Result& res) {
    Reply r;
    if (!res) return r;
    r.status = res->status;
    r.raw = res->body;
    r.headers = res->headers;
    r.body = nlohmann::json::parse(res->body, nullptr, false);
    return r;
  }
  int port_;
};

/// Polls `done` every 20 ms until it holds or `timeout` passes; true when it held. The
/// timeout only bounds a hung test: on two busy cores a run can take ten times its idle time.
inline bool wait_until(const std::function<bool()>& done,
                       std::chrono::milliseconds timeout = scaled(std::chrono::seconds(120))) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return done();
}

/// Reads GET /events on its own thread and keeps every message (type and data).
class EventStreamReader {
 public:
  struct Message {
    std::string type;
    nlohmann::json data;
    std::string id;  ///< the stream's last event id at this message
  };

  explicit EventStreamReader(int port)
      : client_("127.0.0.1", port), parser_([this](const wire::SseEvent& m) {
          std::lock_guard lock(mutex_);
          messages_.push_back({m.type, nlohmann::json::parse(m.data, nullptr, false), m.id});
          return true;
        }) {
    client_.set_read_timeout(5, 0);
    thread_ = std::thread([this] {
      client_.Get("/events", [this](const char* data, std::size_t n) {
        return parser_.feed({data, n}) && !stop_;
      });
    });
  }
  ~EventStreamReader() {
    stop_ = true;
    client_.stop();
    thread_.join();
  }
  std::vector<Message> messages() const {
    std::lock_guard lock(mutex_);
    return messages_;
  }
  bool saw(const std::function<bool(const Message&)>& pred) const {
    std::lock_guard lock(mutex_);
    for (const auto& m : messages_) {
      if (pred(m)) return true;
    }
    return false;
  }

 private:
  httplib::Client client_;
  wire::SseDecoder parser_;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;
  std::vector<Message> messages_;
  std::thread thread_;
};

#ifdef CALSTANDD_BIN
// calstandd started with --listen LISTEN (any free loopback port by default); the port is read
// from its first stdout line.
class DaemonProcess {
 public:
  /// `extra_args` follow the database and listen address; `env` is set in the daemon's
  /// environment only.
  DaemonProcess(const std::string& db, const std::string& log,
                const std::string& listen = "127.0.0.1:0",
                const std::vector<std::string>& extra_args = {},
                const std::vector<std::pair<std::string, std::string>>& env = {}) {
    int out[2];
    if (pipe(out) != 0) return;
    std::vector<std::string> args{CALSTANDD_BIN, "--db", db, "--listen", listen};
    args.insert(args.end(), extra_args.begin(), extra_args.end());
    const pid_t parent = getpid();
    pid_ = fork();
    if (pid_ == 0) {
      die_with_parent(parent);
      dup2(out[1], STDOUT_FILENO);
      const int err = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      dup2(err, STDERR_FILENO);
      close(out[0]);
      setenv("CALSTAND_TOKEN", kTestToken, 1);
      for (const auto& [name, value] : env) setenv(name.c_str(), value.c_str(), 1);
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execv(CALSTANDD_BIN, argv.data());
      _exit(127);
    }
    close(out[1]);
    std::string line;
    char c = 0;
    while (read(out[0], &c, 1) == 1 && c != '\n') line += c;
    close(out[0]);
    const auto colon = line.rfind(':');
    if (line.find("listening on") != std::string::npos && colon != std::string::npos) {
      port_ = std::atoi(line.c_str() + colon + 1);
    }
  }
  ~DaemonProcess() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  int port() const { return port_; }
  pid_t pid() const { return pid_; }
  /// Sends `sig` (none when 0) and waits for the process; its exit code (-signal when killed by
  /// one).
  int signal_and_wait(int sig) {
    if (sig != 0) kill(pid_, sig);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  }

 private:
  pid_t pid_ = -1;
  int port_ = 0;
};

#endif  // CALSTANDD_BIN

/// A loopback port free now (the kernel's pick, released at once): for a daemon that must come
/// back on the same port after a restart.
inline int free_loopback_port() {
  const int sock = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  socklen_t len = sizeof addr;
  int port = 0;
  if (::bind(sock, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0 &&
      ::getsockname(sock, reinterpret_cast<sockaddr*>(&addr), &len) == 0) {
    port = ntohs(addr.sin_port);
  }
  ::close(sock);
  return port;
}

}  // namespace calstand::testing

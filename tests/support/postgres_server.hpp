#pragma once
// A throw-away PostgreSQL server for the fleet tests: initdb into a temporary folder, listening
// on a unix socket in that folder only (no TCP port to collide with), started and stopped with
// pg_ctl. The server refuses to run as root, so under root it runs as `nobody` (runuser).
// Passwords are scram-sha-256: the stations log in as they would in a factory.

#include <glob.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

namespace calstand::testing {

/// Where initdb and pg_ctl are: PATH first, then Debian's /usr/lib/postgresql/<version>/bin
/// (the `postgresql` package does not put them on PATH). Empty when there is no server.
inline std::string find_postgres_bin_dir() {
  if (const char* path = std::getenv("PATH")) {
    std::string p = path;
    std::size_t from = 0;
    while (from <= p.size()) {
      const std::size_t colon = p.find(':', from);
      const std::string dir = p.substr(from, colon == std::string::npos ? colon : colon - from);
      if (!dir.empty() && ::access((dir + "/initdb").c_str(), X_OK) == 0 &&
          ::access((dir + "/pg_ctl").c_str(), X_OK) == 0) {
        return dir;
      }
      if (colon == std::string::npos) break;
      from = colon + 1;
    }
  }
  glob_t found{};
  std::string dir;
  if (::glob("/usr/lib/postgresql/*/bin/initdb", 0, nullptr, &found) == 0 && found.gl_pathc > 0) {
    // The newest version: glob sorts, and versions here are 2 digits (13, 14, 15, ...).
    dir = std::filesystem::path(found.gl_pathv[found.gl_pathc - 1]).parent_path().string();
  }
  ::globfree(&found);
  return dir;
}

class PostgresServer {
 public:
  static constexpr const char* kOwner = "fleet_owner";
  static constexpr int kPort = 5432;  // only names the socket file: no TCP listener

  /// Makes the cluster in `dir` (created; removed by the destructor) and starts it. `error()`
  /// says why when it could not.
  PostgresServer(std::string bin_dir, std::string dir)
      : bin_dir_(std::move(bin_dir)), dir_(std::move(dir)) {
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    as_user_ = ::geteuid() == 0 ? "runuser -u nobody -- " : "";
    const std::string owner_pw = dir_ + "/owner.pw";
    std::ofstream(owner_pw) << owner_password_ << "\n";
    if (::geteuid() == 0) {
      // The server's user owns its folder; the test (root) still reads and writes everything.
      if (std::system(("chown nobody " + dir_ + " " + owner_pw).c_str()) != 0) {
        error_ = "chown nobody failed";
        return;
      }
    }
    if (!sh(as_user_ + bin_dir_ + "/initdb -D " + dir_ + "/data -U " + kOwner +
            " --auth=scram-sha-256 --pwfile=" + owner_pw + " > " + dir_ + "/initdb.log 2>&1")) {
      error_ = "initdb failed: see " + dir_ + "/initdb.log";
      return;
    }
    write_passfile(kOwner, owner_password_);
    if (!start()) error_ = "pg_ctl start failed: see " + dir_ + "/server.log";
  }
  ~PostgresServer() {
    stop();
    std::filesystem::remove_all(dir_);
  }
  PostgresServer(const PostgresServer&) = delete;
  PostgresServer& operator=(const PostgresServer&) = delete;

  const std::string& error() const { return error_; }

  bool start() {
    running_ =
        sh(as_user_ + bin_dir_ + "/pg_ctl -D " + dir_ + "/data -l " + dir_ +
           "/server.log -w -t 60 -o \"-c listen_addresses='' -c unix_socket_directories=" + dir_ +
           " -p " + std::to_string(kPort) + "\" start > /dev/null 2>&1");
    return running_;
  }
  /// Stops the server; `mode` is pg_ctl's: fast (sessions are ended, their transactions rolled
  /// back) or immediate (as a power cut of the server).
  bool stop(const std::string& mode = "fast") {
    if (!running_) return true;
    running_ = false;
    return sh(as_user_ + bin_dir_ + "/pg_ctl -D " + dir_ + "/data -m " + mode +
              " -w -t 60 stop > /dev/null 2>&1");
  }

  /// The password file (mode 600, libpq's .pgpass format) with every role's password.
  const std::string& passfile() const { return passfile_; }
  /// A login role `name` with a random password, added to the password file.
  void add_password(const std::string& role, const std::string& password) {
    write_passfile(role, password);
  }

  /// `postgresql://ROLE@%2FSOCKET%2FDIR:PORT/DBNAME`: no password (it is in passfile()).
  std::string url(const std::string& role, const std::string& dbname) const {
    // The socket folder percent-encoded as the host: no character a shell would take.
    std::string host;
    for (char c : dir_) host += c == '/' ? std::string("%2F") : std::string(1, c);
    return "postgresql://" + role + "@" + host + ":" + std::to_string(kPort) + "/" + dbname;
  }
  /// A libpq keyword/value string for a test's own connection.
  std::string conninfo(const std::string& role, const std::string& dbname) const {
    return "host=" + dir_ + " port=" + std::to_string(kPort) + " user=" + role +
           " dbname=" + dbname + " passfile=" + passfile_;
  }

 private:
  static bool sh(const std::string& command) { return std::system(command.c_str()) == 0; }

  void write_passfile(const std::string& role, const std::string& password) {
    passfile_ = dir_ + "/test.pgpass";
    std::ofstream(passfile_, std::ios::app) << "*:*:*:" << role << ":" << password << "\n";
    ::chmod(passfile_.c_str(), 0600);
  }

  std::string bin_dir_;
  std::string dir_;
  std::string as_user_;
  std::string owner_password_ = "owner-" + std::to_string(::getpid());
  std::string passfile_;
  std::string error_;
  bool running_ = false;
};

}  // namespace calstand::testing

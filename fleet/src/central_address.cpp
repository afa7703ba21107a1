#include "fleet/central_address.hpp"

#include <fmt/format.h>
#include <libpq-fe.h>
#include <sys/stat.h>

#include <map>

#include "core/error.hpp"
#include "fleet/central_error.hpp"

namespace calstand::fleet {
namespace {

// A libpq connection-string value in single quotes, backslash and quote escaped.
std::string quoted(const std::string& value) {
  std::string out = "'";
  for (char c : value) {
    if (c == '\'' || c == '\\') out += '\\';
    out += c;
  }
  return out + "'";
}

// Every setting of `url` that is set, by keyword, parsed by libpq itself (URL or keyword/value
// form alike).
std::map<std::string, std::string> parse_settings(const std::string& url,
                                                  const std::string& where) {
  char* message = nullptr;
  PQconninfoOption* options = PQconninfoParse(url.c_str(), &message);
  if (options == nullptr) {
    std::string why = message ? message : "out of memory";
    PQfreemem(message);
    while (!why.empty() && why.back() == '\n') why.pop_back();
    throw core::InputError(where, "not a PostgreSQL connection URL: " + why);
  }
  std::map<std::string, std::string> settings;
  for (const PQconninfoOption* o = options; o->keyword != nullptr; ++o) {
    if (o->val != nullptr && *o->val != '\0') settings[o->keyword] = o->val;
  }
  PQconninfoFree(options);
  return settings;
}

bool is_local_host(const std::string& host) {
  // No host: libpq's default unix socket. A path (or an abstract socket, @name): a unix socket.
  return host.empty() || host.front() == '/' || host.front() == '@' || host == "localhost" ||
         host == "127.0.0.1" || host == "::1";
}

void check_password_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
    throw core::InputError("--password-file " + path, "no such file");
  }
  if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    throw core::InputError(
        "--password-file " + path,
        fmt::format("readable by group or others (mode {:04o}); libpq ignores such a password "
                    "file: chmod 600 it",
                    st.st_mode & 07777));
  }
}

}  // namespace

CentralAddress parse_central_address(const std::string& url, const std::string& password_file,
                                     const std::string& where) {
  if (url.empty()) throw core::InputError(where, "empty address");
  std::map<std::string, std::string> settings = parse_settings(url, where);
  if (settings.count("password") != 0) {
    throw core::InputError(
        where,
        "the address holds a password; a command line is readable by every user of this machine "
        "(ps, /proc/PID/cmdline, shell history): put it in a password file (--password-file, "
        "libpq's .pgpass format) or in PGPASSWORD instead");
  }
  CentralAddress address;
  // A list of hosts (failover) is local only when every one of them is.
  const std::string hosts = settings.count("host") ? settings["host"] : settings["hostaddr"];
  address.local = true;
  std::size_t from = 0;
  do {
    const std::size_t comma = hosts.find(',', from);
    const std::string host = hosts.substr(from, comma == std::string::npos ? comma : comma - from);
    address.local = address.local && is_local_host(host);
    from = comma == std::string::npos ? comma : comma + 1;
  } while (from != std::string::npos);
  if (!address.local) {
    const std::string mode = settings.count("sslmode") ? settings["sslmode"] : "";
    if (mode.empty()) {
      settings["sslmode"] = "require";
    } else if (mode == "disable" || mode == "allow" || mode == "prefer") {
      throw core::InputError(
          where, fmt::format("sslmode={} to {}: the connection could be unencrypted; a central "
                             "database off this machine needs TLS (sslmode=require, verify-ca "
                             "or verify-full)",
                             mode, hosts));
    }
  }
  if (!password_file.empty()) {
    check_password_file(password_file);
    settings["passfile"] = password_file;
  }
  for (const auto& [keyword, value] : settings) {
    if (!address.conninfo.empty()) address.conninfo += ' ';
    address.conninfo += keyword + "=" + quoted(value);
  }
  address.display = fmt::format("{}{}{}/{}", settings.count("user") ? settings["user"] + "@" : "",
                                hosts.empty() ? "(default socket)" : hosts,
                                settings.count("port") ? ":" + settings["port"] : "",
                                settings.count("dbname") ? settings["dbname"] : "");
  return address;
}

std::unique_ptr<pqxx::connection> connect_central(const CentralAddress& address) {
  try {
    return std::make_unique<pqxx::connection>(address.conninfo);
  } catch (...) {
    rethrow_as_central("connect to " + address.display);
  }
}

}  // namespace calstand::fleet

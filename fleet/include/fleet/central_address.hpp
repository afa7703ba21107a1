#pragma once
// Where the central database is and how to reach it safely: a libpq URL
// (postgresql://user@host:port/dbname?...) checked before anything connects.

#include <memory>
#include <pqxx/connection>
#include <string>

namespace calstand::fleet {

/// A checked central database address.
struct CentralAddress {
  /// libpq keyword/value connection string: the URL's settings, sslmode=require added for a
  /// server off this machine, passfile when a password file was given. Never a password.
  std::string conninfo;
  /// For messages: `user@host:port/dbname` (no secret).
  std::string display;
  /// The server is on this machine (unix socket, localhost, 127.0.0.1, ::1): no TLS needed.
  bool local = false;
};

/// Checks `url` (`where` names the option it came from, e.g. `--to`) and `password_file`
/// (empty: none; libpq then reads PGPASSFILE, ~/.pgpass or PGPASSWORD, as it always does).
///
/// Throws core::InputError naming where and why when:
///  - the URL is not one libpq can parse;
///  - it holds a password (a command line is readable by every user of the machine: ps,
///    /proc/PID/cmdline, shell history): give it in a password file or PGPASSWORD instead;
///  - the server is not local and sslmode is disable, allow or prefer (the connection could be
///    unencrypted); when sslmode is not given for such a server it becomes `require`;
///  - the password file does not exist or is readable by group or others (libpq ignores such a
///    file with only a warning, and the sync would fail later with a puzzling "no password").
CentralAddress parse_central_address(const std::string& url, const std::string& password_file,
                                     const std::string& where);

/// Opens a connection; throws CentralError (operation `connect to DISPLAY`) when the server
/// cannot be reached or refuses the login.
std::unique_ptr<pqxx::connection> connect_central(const CentralAddress& address);

}  // namespace calstand::fleet

#pragma once

// Helpers the route files share: JSON responses, request bodies, ids, error mapping.

// clang-format off
#include <Eigen/Core>  // before httplib.h: its <resolv.h> defines a macro `_res`, a name Eigen uses
#include <httplib.h>
// clang-format on
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>

namespace calstand::daemon::api {

/// A request the API cannot use: answered with `status`, `where` naming the part at fault.
class BadRequest : public std::runtime_error {
 public:
  BadRequest(int status, std::string where, const std::string& why)
      : std::runtime_error(why), status_(status), where_(std::move(where)) {}
  int status() const { return status_; }
  const std::string& where() const { return where_; }

 private:
  int status_;
  std::string where_;
};

void send_json(httplib::Response& res, int status, const nlohmann::json& body);
/// {"error": why, "where": where} with `status`.
void send_error(httplib::Response& res, int status, const std::string& where,
                const std::string& why);

/// Request bodies nested deeper than this are refused (400).
inline constexpr int kMaxJsonDepth = 64;

/// The body as JSON; an empty body is `empty_as` when given. Throws BadRequest 400 naming the
/// line and column of a syntax error, or saying the body is nested deeper than kMaxJsonDepth.
nlohmann::json parse_json_body(const httplib::Request& req,
                               const std::optional<nlohmann::json>& empty_as = std::nullopt);

/// The run or calibration id of a route `/.../(\d+)...`; throws BadRequest 404 when it is out
/// of range (no such id can exist).
std::int64_t id_from_path(const httplib::Request& req, std::size_t match = 1);

/// The query parameter `name` as an integer in [min, max]; nullopt when absent. Throws
/// BadRequest 400 naming `?name` when it is not a whole number in range.
std::optional<std::int64_t> int_param(const httplib::Request& req, const std::string& name,
                                      std::int64_t min, std::int64_t max);

/// Wraps a handler so that no exception leaves it: BadRequest -> its status, a procedure
/// error -> 422 with every violation, ActionRefused -> 409, core::InputError -> 400, anything
/// else -> 500 (logged).
httplib::Server::Handler guarded(
    std::function<void(const httplib::Request&, httplib::Response&)> fn);

}  // namespace calstand::daemon::api

#include "http_util.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <charconv>

#include "core/error.hpp"
#include "daemon/service/run_service.hpp"
#include "procedures/procedure.hpp"

namespace calstand::daemon::api {

void send_json(httplib::Response& res, int status, const nlohmann::json& body) {
  res.status = status;
  // Replace invalid UTF-8 (e.g. echoed from a client) instead of throwing while answering.
  res.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n",
                  "application/json");
}

void send_error(httplib::Response& res, int status, const std::string& where,
                const std::string& why) {
  nlohmann::json body = {{"error", why}};
  if (!where.empty()) body["where"] = where;
  send_json(res, status, body);
}

nlohmann::json parse_json_body(const httplib::Request& req,
                               const std::optional<nlohmann::json>& empty_as) {
  if (req.body.empty() && empty_as) return *empty_as;
  // Copying, printing and validating a JSON value recurse once per level: a body of a million
  // '[' would overflow the handler's stack. No request needs more than a few levels.
  const nlohmann::json::parser_callback_t depth_limit = [](int depth, nlohmann::json::parse_event_t,
                                                           nlohmann::json&) {
    if (depth >= kMaxJsonDepth) {  // the outermost value is at depth 0
      throw BadRequest(400, "body",
                       fmt::format("JSON nested deeper than {} levels", kMaxJsonDepth));
    }
    return true;
  };
  try {
    return nlohmann::json::parse(req.body, depth_limit);
  } catch (const nlohmann::json::parse_error& e) {
    // e.byte is 1-based; turn it into line and column for people.
    std::size_t line = 1;
    std::size_t column = 1;
    const std::size_t end = std::min<std::size_t>(e.byte > 0 ? e.byte - 1 : 0, req.body.size());
    for (std::size_t i = 0; i < end; ++i) {
      if (req.body[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    throw BadRequest(400, fmt::format("body: line {}, column {} (byte {})", line, column, e.byte),
                     fmt::format("malformed JSON: {}", e.what()));
  }
}

std::int64_t id_from_path(const httplib::Request& req, std::size_t match) {
  const std::string text = req.matches[match];
  std::int64_t id = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), id);
  if (ec != std::errc() || ptr != text.data() + text.size() || id <= 0) {
    throw BadRequest(404, req.path, fmt::format("no such id: {}", text));
  }
  return id;
}

std::optional<std::int64_t> int_param(const httplib::Request& req, const std::string& name,
                                      std::int64_t min, std::int64_t max) {
  if (!req.has_param(name)) return std::nullopt;
  const std::string text = req.get_param_value(name);
  std::int64_t value = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || ptr != text.data() + text.size() || value < min || value > max) {
    throw BadRequest(
        400, "?" + name,
        fmt::format("must be a whole number from {} to {} (got \"{}\")", min, max, text));
  }
  return value;
}

httplib::Server::Handler guarded(
    std::function<void(const httplib::Request&, httplib::Response&)> fn) {
  return [fn = std::move(fn)](const httplib::Request& req, httplib::Response& res) {
    try {
      fn(req, res);
    } catch (const BadRequest& e) {
      send_error(res, e.status(), e.where(), e.what());
    } catch (const procedures::ProcedureError& e) {
      nlohmann::json violations = nlohmann::json::array();
      for (const auto& v : e.violations())
        violations.push_back({{"path", v.path}, {"message", v.message}});
      send_json(res, 422,
                {{"error", "invalid procedure"}, {"where", e.where()}, {"violations", violations}});
    } catch (const service::ActionRefused& e) {
      send_error(res, 409, req.path, e.what());
    } catch (const service::OutOfSpace& e) {
      send_error(res, 507, req.path, e.what());  // Insufficient Storage
    } catch (const core::InputError& e) {
      send_error(res, 400, e.where(), e.what());
    } catch (const std::exception& e) {
      spdlog::error("{} {}: {}", req.method, req.path, e.what());
      send_error(res, 500, req.path, std::string("internal error: ") + e.what());
    }
  };
}

}  // namespace calstand::daemon::api

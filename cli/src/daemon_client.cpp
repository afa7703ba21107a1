#include "daemon_client.hpp"

#include <fmt/format.h>
#include <Eigen/Core>  // before httplib.h: its <resolv.h> defines a macro `_res`, a name Eigen uses
#include <httplib.h>

#include <cstdlib>
#include <fstream>
#include <stdexcept>

#include "core/error.hpp"
#include "daemon/api/api_server.hpp"

namespace calstand::cli {
namespace {

std::string read_token(const std::string& file) {
  if (file.empty()) {
    const char* env = std::getenv("CALSTAND_TOKEN");
    return env ? env : "";
  }
  std::ifstream in(file);
  if (!in) throw core::InputError(file, "cannot read the token file");
  std::string token;
  std::getline(in, token);
  while (!token.empty() && std::isspace(static_cast<unsigned char>(token.back()))) token.pop_back();
  return token;
}

// The daemon's answer, or an error that says what the daemon said.
nlohmann::json answer(const httplib::Result& res, const std::string& what, const std::string& where) {
  if (!res) {
    throw std::runtime_error(fmt::format("{}: no answer from calstandd at {} ({})", what, where,
                                         httplib::to_string(res.error())));
  }
  nlohmann::json body = nlohmann::json::parse(res->body, nullptr, false);
  if (res->status < 400) return body;
  std::string message = body.is_object() ? body.value("error", res->body) : res->body;
  if (body.is_object() && body.contains("where")) message = body["where"].get<std::string>() + ": " + message;
  if (body.is_object() && body.contains("violations")) {
    for (const auto& v : body["violations"]) {
      message += fmt::format("\n  {}: {}", v.value("path", ""), v.value("message", ""));
    }
  }
  const std::string text = fmt::format("{} (HTTP {}): {}", what, res->status, message);
  if (res->status >= 500) throw std::runtime_error(text);
  throw core::InputError("", text);
}

}  // namespace

void add_daemon_options(CLI::App& cmd, DaemonAddress& address) {
  cmd.add_option("--daemon", address.daemon, "calstandd address HOST:PORT")->capture_default_str();
  cmd.add_option("--token-file", address.token_file, "Bearer token file (else env CALSTAND_TOKEN)");
  cmd.add_option("--operator", address.operator_name, "Name recorded with the action (default $USER)");
}

DaemonClient::DaemonClient(const DaemonAddress& address) {
  std::tie(host_, port_) = daemon::api::parse_listen_address(address.daemon);
  token_ = read_token(address.token_file);
  operator_ = address.operator_name;
  if (operator_.empty()) {
    const char* user = std::getenv("USER");
    operator_ = user ? user : "";
  }
}

nlohmann::json DaemonClient::get(const std::string& path) const {
  httplib::Client c(host_, port_);
  c.set_read_timeout(30, 0);
  return answer(c.Get(path.c_str()), "GET " + path, fmt::format("{}:{}", host_, port_));
}

nlohmann::json DaemonClient::post(const std::string& path, const nlohmann::json& body) const {
  httplib::Client c(host_, port_);
  c.set_read_timeout(30, 0);
  httplib::Headers headers;
  if (!token_.empty()) headers.emplace("Authorization", "Bearer " + token_);
  if (!operator_.empty()) headers.emplace("X-Calstand-Operator", operator_);
  return answer(c.Post(path.c_str(), headers, body.dump(), "application/json"), "POST " + path,
                fmt::format("{}:{}", host_, port_));
}

void DaemonClient::stream_events(
    const std::function<bool(const std::string&, const nlohmann::json&)>& on_message) const {
  httplib::Client c(host_, port_);
  c.set_read_timeout(10, 0);  // the daemon sends a keep-alive every second
  std::string buffer;
  bool stopped = false;
  const auto res = c.Get("/events", [&](const char* data, std::size_t n) {
    buffer.append(data, n);
    for (std::size_t end; (end = buffer.find("\n\n")) != std::string::npos;) {
      const std::string block = buffer.substr(0, end);
      buffer.erase(0, end + 2);
      std::string type;
      nlohmann::json payload;
      std::size_t pos = 0;
      while (pos < block.size()) {
        auto eol = block.find('\n', pos);
        if (eol == std::string::npos) eol = block.size();
        const std::string line = block.substr(pos, eol - pos);
        if (line.rfind("event: ", 0) == 0) type = line.substr(7);
        if (line.rfind("data: ", 0) == 0) payload = nlohmann::json::parse(line.substr(6), nullptr, false);
        pos = eol + 1;
      }
      if (!type.empty() && !on_message(type, payload)) {
        stopped = true;
        return false;
      }
    }
    return true;
  });
  if (!res && !stopped) {
    throw std::runtime_error(fmt::format("GET /events: the stream from calstandd at {}:{} ended ({})",
                                         host_, port_, httplib::to_string(res.error())));
  }
}

}  // namespace calstand::cli

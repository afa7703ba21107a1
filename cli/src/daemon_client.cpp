#include "daemon_client.hpp"

// clang-format off
#include <Eigen/Core>  // before httplib.h: its <resolv.h> defines a macro `_res`, a name Eigen uses
#include <httplib.h>
// clang-format on
#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "core/error.hpp"
#include "wire/listen_address.hpp"
#include "wire/sse_decoder.hpp"

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
nlohmann::json answer(const httplib::Result& res, const std::string& what,
                      const std::string& where) {
  if (!res) {
    throw std::runtime_error(fmt::format("{}: no answer from calstandd at {} ({})", what, where,
                                         httplib::to_string(res.error())));
  }
  nlohmann::json body = nlohmann::json::parse(res->body, nullptr, false);
  if (res->status < 400) return body;
  std::string message = body.is_object() ? body.value("error", res->body) : res->body;
  if (body.is_object() && body.contains("where"))
    message = body["where"].get<std::string>() + ": " + message;
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
  cmd.add_option("--operator", address.operator_name,
                 "Name recorded with the action (default $USER)");
}

DaemonClient::DaemonClient(const DaemonAddress& address) {
  std::tie(host_, port_) = wire::parse_listen_address(address.daemon, "--daemon");
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
    double reconnect_s,
    const std::function<bool(const std::string&, const nlohmann::json&)>& on_message) const {
  std::string last_id;  // of the last message with an id: where a reconnection resumes
  auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(reconnect_s);
  for (;;) {
    httplib::Client c(host_, port_);
    c.set_read_timeout(10, 0);  // the daemon sends a keep-alive every second
    httplib::Headers headers;
    if (!last_id.empty()) headers.emplace("Last-Event-ID", last_id);
    bool stopped = false;
    bool received = false;  // anything: the daemon was up, the reconnection window starts again
    wire::SseDecoder parser([&](const wire::SseEvent& m) {
      if (!m.id.empty()) last_id = m.id;
      if (on_message(m.type, nlohmann::json::parse(m.data, nullptr, false))) return true;
      stopped = true;
      return false;
    });
    const auto res = c.Get("/events", headers, [&](const char* data, std::size_t n) {
      received = true;
      return parser.feed({data, n});
    });
    if (stopped) return;
    // A stream that broke mid-body gives no response, only the bytes it delivered.
    const bool connected = received || (res && res->status == 200);
    if (connected) {
      // It was up: the reconnection window counts from the break.
      give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(reconnect_s);
    }
    if (std::chrono::steady_clock::now() >= give_up) {
      throw std::runtime_error(fmt::format(
          "GET /events: the stream from calstandd at {}:{} ended ({}) and did not come back within "
          "{:.0f} s",
          host_, port_, res ? fmt::format("HTTP {}", res->status) : httplib::to_string(res.error()),
          reconnect_s));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
}

}  // namespace calstand::cli

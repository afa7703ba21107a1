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
  cmd.add_option("--daemon", address.daemon,
                 "calstandd address HOST:PORT, or https://HOST:PORT for a daemon serving TLS")
      ->capture_default_str();
  cmd.add_option("--token-file", address.token_file, "Bearer token file (else env CALSTAND_TOKEN)");
  cmd.add_option("--ca-file", address.ca_file,
                 "CA certificate (PEM) an https daemon's certificate is checked against (else "
                 "env CALSTAND_CA_FILE, else the system's); --ca-file implies https");
  cmd.add_option("--operator", address.operator_name,
                 "Name recorded with the action (default $USER)");
}

DaemonClient::DaemonClient(const DaemonAddress& address) {
  ca_file_ = address.ca_file;
  if (ca_file_.empty()) {
    const char* env = std::getenv("CALSTAND_CA_FILE");
    ca_file_ = env ? env : "";
  }
  if (!ca_file_.empty() && !std::ifstream(ca_file_)) {
    throw core::InputError(address.ca_file.empty() ? "CALSTAND_CA_FILE" : "--ca-file",
                           fmt::format("cannot read {}", ca_file_));
  }
  // An explicit --ca-file means https; the environment's CA file only serves an https address
  // (a shell that exports it still reaches a plain loopback daemon).
  endpoint_ = wire::parse_daemon_address(address.daemon, "--daemon", !address.ca_file.empty());
  token_ = read_token(address.token_file);
  operator_ = address.operator_name;
  if (operator_.empty()) {
    const char* user = std::getenv("USER");
    operator_ = user ? user : "";
  }
}

std::unique_ptr<httplib::Client> DaemonClient::connect(int read_timeout_s) const {
  auto c = std::make_unique<httplib::Client>(endpoint_.url());
  c->set_read_timeout(read_timeout_s, 0);
  if (endpoint_.tls) {
    if (!ca_file_.empty()) c->set_ca_cert_path(ca_file_.c_str());
    c->enable_server_certificate_verification(true);
  }
  if (!token_.empty()) c->set_bearer_token_auth(token_.c_str());
  return c;
}

nlohmann::json DaemonClient::get(const std::string& path) const {
  return answer(connect(30)->Get(path.c_str()), "GET " + path, endpoint_.url());
}

nlohmann::json DaemonClient::post(const std::string& path, const nlohmann::json& body) const {
  httplib::Headers headers;
  if (!operator_.empty()) headers.emplace("X-Calstand-Operator", operator_);
  return answer(connect(30)->Post(path.c_str(), headers, body.dump(), "application/json"),
                "POST " + path, endpoint_.url());
}

void DaemonClient::stream_events(
    double reconnect_s,
    const std::function<bool(const std::string&, const nlohmann::json&)>& on_message) const {
  std::string last_id;  // of the last message with an id: where a reconnection resumes
  auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(reconnect_s);
  for (;;) {
    const auto client = connect(10);  // the daemon sends a keep-alive every second
    httplib::Client& c = *client;
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
    int status = 0;
    const auto res = c.Get(
        "/events", headers,
        [&](const httplib::Response& r) {
          status = r.status;
          return r.status == 200;  // a refusal's body is not a stream
        },
        [&](const char* data, std::size_t n) {
          received = true;
          return parser.feed({data, n});
        });
    if (stopped) return;
    // A refused token stays refused: say so at once rather than retry for the whole window.
    if (status == 401 || status == 403) {
      throw core::InputError(
          "", fmt::format("GET /events (HTTP {}): calstandd at {} refused the token ({})", status,
                          endpoint_.url(),
                          token_.empty() ? "none given: --token-file or CALSTAND_TOKEN"
                                         : "--token-file or CALSTAND_TOKEN"));
    }
    // A stream that broke mid-body gives no response, only the bytes it delivered.
    const bool connected = received || (res && res->status == 200);
    if (connected) {
      // It was up: the reconnection window counts from the break.
      give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(reconnect_s);
    }
    if (std::chrono::steady_clock::now() >= give_up) {
      throw std::runtime_error(fmt::format(
          "GET /events: the stream from calstandd at {} ended ({}) and did not come back within "
          "{:.0f} s",
          endpoint_.url(),
          res ? fmt::format("HTTP {}", res->status) : httplib::to_string(res.error()),
          reconnect_s));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
}

}  // namespace calstand::cli

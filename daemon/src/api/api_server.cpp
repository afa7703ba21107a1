#include "daemon/api/api_server.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>

#include <thread>

#include "core/error.hpp"
#include "daemon/api/access.hpp"
#include "http_util.hpp"
#include "routes.hpp"

namespace calstand::daemon::api {
namespace {

// Connections waiting to be accepted: room for every client of a busy lab connecting at once.
constexpr int kListenBacklog = 128;

}  // namespace

void ApiOptions::validate() const {
  if (!is_loopback_address(host) && token.empty()) {
    throw core::InputError("--listen", fmt::format("{} is beyond loopback: a token is required "
                                                   "(--token-file or CALSTAND_TOKEN)",
                                                   host));
  }
  if (port < 0 || port > 65535)
    throw core::InputError("--listen", fmt::format("port {} is not 0..65535", port));
  if (threads < 1) throw core::InputError("threads", "at least one connection thread is needed");
  if (max_body_bytes == 0) throw core::InputError("max_body_bytes", "must be > 0");
  if (max_streams < 1 || max_streams >= threads) {
    throw core::InputError(
        "max_streams",
        fmt::format("{} live streams on {} threads: need 1 .. threads - 1", max_streams, threads));
  }
}

struct ApiServer::Impl {
  Impl(service::RunService& service, service::EventHub& hub, ApiOptions opts)
      : options(std::move(opts)),
        ctx{service, hub, service.options().db_path, options.max_streams} {}

  ApiOptions options;
  RouteContext ctx;
  httplib::Server server;
  std::thread listener;
  socket_t listen_socket = -1;  // set while binding (set_socket_options)
};

ApiServer::ApiServer(service::RunService& service, service::EventHub& hub, ApiOptions options) {
  options.validate();
  impl_ = std::make_unique<Impl>(service, hub, std::move(options));
  auto& server = impl_->server;
  const int threads = impl_->options.threads;
  server.new_task_queue = [threads] {
    return new httplib::ThreadPool(static_cast<std::size_t>(threads));
  };
  server.set_payload_max_length(impl_->options.max_body_bytes);
  // Small JSON answers on kept-alive connections: without TCP_NODELAY each waits for the
  // client's delayed ACK (~40 ms). httplib closes a connection after 5 requests by default,
  // and its listen backlog is 5: pollers reconnecting together would see dropped SYNs (1 s).
  server.set_tcp_nodelay(true);
  server.set_keep_alive_max_count(1000);
  // The listening socket is remembered so start() can lengthen its accept queue (httplib's is
  // compiled in at 5, and a burst of clients connecting at once would wait 1 s for a SYN retry).
  server.set_socket_options([this](socket_t sock) {
    // SO_REUSEADDR (a restart binds at once, past TIME_WAIT) but not httplib's default
    // SO_REUSEPORT, with which a second daemon would bind the same port and silently take
    // half of the requests.
    const int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    impl_->listen_socket = sock;
  });

  // Every mutating request carries the token when one is configured; reads stay open so a
  // status display needs no secret (they reveal no more than the lab's station screen).
  server.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    if (req.method == "GET" || req.method == "HEAD")
      return httplib::Server::HandlerResponse::Unhandled;
    if (bearer_token_accepted(req.get_header_value("Authorization"), impl_->options.token)) {
      return httplib::Server::HandlerResponse::Unhandled;
    }
    res.set_header("WWW-Authenticate", "Bearer");
    send_error(res, 401, "Authorization", "a valid bearer token is required for this request");
    return httplib::Server::HandlerResponse::Handled;
  });
  // Answers httplib produced without a body (unknown route, body too large, ...) get a JSON
  // body saying why; answers of the handlers keep theirs.
  server.set_error_handler(
      httplib::Server::HandlerWithResponse([](const httplib::Request& req, httplib::Response& res) {
        if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
        std::string why = "request refused";
        if (res.status == 400) why = "malformed request";
        if (res.status == 404) why = "no such resource";
        if (res.status == 405) why = "method not allowed";
        if (res.status == 413) why = "request body too large";
        if (res.status == 414) why = "request URI too long";
        send_error(res, res.status, req.method + " " + req.path, why);
        return httplib::Server::HandlerResponse::Handled;
      }));
  server.set_exception_handler(
      [](const httplib::Request& req, httplib::Response& res, std::exception_ptr ep) {
        std::string why = "unknown error";
        try {
          if (ep) std::rethrow_exception(ep);
        } catch (const std::exception& e) {
          why = e.what();
        } catch (...) {
        }
        spdlog::error("{} {}: {}", req.method, req.path, why);
        send_error(res, 500, req.path, "internal error: " + why);
      });
  server.set_logger([](const httplib::Request& req, const httplib::Response& res) {
    spdlog::debug("{} {} {} -> {}", req.remote_addr, req.method, req.path, res.status);
  });
  register_run_routes(server, impl_->ctx);
  register_station_routes(server, impl_->ctx);
  register_procedure_routes(server, impl_->ctx);
  register_console_routes(server, impl_->ctx);
  register_analysis_routes(server, impl_->ctx);
}

ApiServer::~ApiServer() { stop(); }

int ApiServer::start() {
  auto& server = impl_->server;
  const auto& o = impl_->options;
  int port = o.port;
  if (port == 0) {
    port = server.bind_to_any_port(o.host);
    if (port < 0)
      throw std::runtime_error(fmt::format("cannot listen on {}: no free port", o.host));
  } else if (!server.bind_to_port(o.host, port)) {
    throw std::runtime_error(fmt::format(
        "cannot listen on {}:{} (in use, or not an address of this machine)", o.host, port));
  }
  if (impl_->listen_socket >= 0) ::listen(impl_->listen_socket, kListenBacklog);  // best effort
  impl_->listener = std::thread([&server] { server.listen_after_bind(); });
  spdlog::info("control API on http://{}:{} ({})", o.host, port,
               o.token.empty() ? "no token: loopback only" : "bearer token required for changes");
  return port;
}

void ApiServer::stop() {
  if (!impl_) return;
  impl_->ctx.hub.close();  // ends live streams, whose threads the server joins
  impl_->server.stop();
  if (impl_->listener.joinable()) impl_->listener.join();
}

}  // namespace calstand::daemon::api

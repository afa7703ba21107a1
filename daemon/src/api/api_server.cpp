#include "daemon/api/api_server.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <thread>

#include "connection_guard.hpp"
#include "core/error.hpp"
#include "daemon/api/access.hpp"
#include "daemon/api/tokens_file.hpp"
#include "http_util.hpp"
#include "request_context.hpp"
#include "routes.hpp"

namespace calstand::daemon::api {
namespace {

// Connections waiting to be accepted: room for every client of a busy lab connecting at once.
constexpr int kListenBacklog = 128;

void require_readable(const std::string& file, const char* option) {
  if (!std::ifstream(file)) {
    throw core::InputError(option, fmt::format("cannot read {}", file));
  }
}

// The server: with TLS when a certificate is given (the files are checked first so that the
// error names the one at fault; OpenSSL then checks that they are PEM and belong together).
// Both guarded (connection_guard.hpp): a deadline per request, a cap per client address.
std::unique_ptr<httplib::Server> make_server(const ApiOptions& o) {
  const GuardLimits limits{o.request_deadline_s, o.max_connections_per_address};
  if (!o.uses_tls()) return std::make_unique<GuardedServer>(limits);
  require_readable(o.tls_cert_file, "--tls-cert");
  require_readable(o.tls_key_file, "--tls-key");
  auto server =
      std::make_unique<GuardedSslServer>(o.tls_cert_file.c_str(), o.tls_key_file.c_str(), limits);
  if (!server->is_valid()) {
    throw core::InputError("--tls-cert", fmt::format("{} and {} are not a PEM certificate chain "
                                                     "and its private key",
                                                     o.tls_cert_file, o.tls_key_file));
  }
  return server;
}

}  // namespace

std::vector<NamedToken> ApiOptions::all_tokens() const {
  std::vector<NamedToken> all = tokens;
  if (!token.empty()) all.push_back({kLegacyTokenName, Role::kOperator, token});
  return all;
}

void ApiOptions::validate() const {
  const bool loopback = is_loopback_address(host);
  const auto all = all_tokens();
  if (!loopback && all.empty()) {
    throw core::InputError("--listen", fmt::format("{} is beyond loopback: a token is required "
                                                   "(--tokens, --token-file or CALSTAND_TOKEN)",
                                                   host));
  }
  check_unique_tokens(all, "--tokens");
  if (tls_cert_file.empty() != tls_key_file.empty()) {
    throw core::InputError(tls_cert_file.empty() ? "--tls-cert" : "--tls-key",
                           "TLS needs both the certificate (--tls-cert) and its key (--tls-key)");
  }
  if (!loopback && !uses_tls() && !allow_plaintext) {
    throw core::InputError("--listen",
                           fmt::format("{} is beyond loopback: TLS is required (--tls-cert and "
                                       "--tls-key), or --allow-plaintext on a network you trust",
                                       host));
  }
  if (port < 0 || port > 65535)
    throw core::InputError("--listen", fmt::format("port {} is not 0..65535", port));
  if (threads < 1) throw core::InputError("threads", "at least one connection thread is needed");
  if (request_deadline_s < 1) {
    throw core::InputError("--request-deadline-s", "must be at least 1 s");
  }
  if (max_connections_per_address < 1 || max_connections_per_address > threads) {
    throw core::InputError("--max-connections-per-address",
                           fmt::format("{}: need 1 .. {} (the connection threads)",
                                       max_connections_per_address, threads));
  }
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
        ctx{service, hub, service.options().db_path, options.max_streams},
        server_ptr(make_server(options)),
        server(*server_ptr) {
    ctx.access.tokens = options.all_tokens();
    ctx.access.reads_need_token = !is_loopback_address(options.host);
    ctx.fleet = options.fleet;
    ctx.publish_status = options.publish_status;
  }

  ApiOptions options;
  RouteContext ctx;
  std::unique_ptr<httplib::Server> server_ptr;  // an httplib::SSLServer with TLS
  httplib::Server& server;
  std::thread listener;
  std::atomic<bool> listener_done{false};  // listen_after_bind() has returned
  socket_t listen_socket = -1;             // set while binding (set_socket_options)
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
  // A slow client (one trickling its request a byte at a time, or idling on a kept-alive
  // connection) holds a connection thread only while it keeps sending within the read
  // timeout; `threads` bounds how many such clients it takes to crowd out the others
  // (schemas/api.md, "Limits").
  server.set_read_timeout(impl_->options.read_timeout_s, 0);
  server.set_keep_alive_timeout(impl_->options.keep_alive_timeout_s);
  // Small JSON answers on kept-alive connections: without TCP_NODELAY each waits for the
  // client's delayed ACK (~40 ms). httplib closes a connection after 5 requests by default,
  // and its listen backlog is 5: pollers reconnecting together would see dropped SYNs (1 s).
  server.set_tcp_nodelay(true);
  // A token may ride in an address (?access_token=, for the console's stream and links): no
  // page the daemon serves hands its address on to another site.
  server.set_default_headers({{"Referrer-Policy", "no-referrer"}});
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

  // Every request is checked here, before any route runs (AccessPolicy: what each needs).
  // On loopback, reads stay open so a status display there needs no secret; beyond it they
  // need a token too.
  server.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    const AccessDecision d =
        check_access(impl_->ctx.access, req.method, req.path, presented_token(req));
    if (d.status == 0) return httplib::Server::HandlerResponse::Unhandled;
    res.set_header("WWW-Authenticate",
                   d.status == 403 ? R"(Bearer error="insufficient_scope")" : "Bearer");
    send_error(res, d.status, "Authorization", d.why);
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
  register_factory_routes(server, impl_->ctx);
  register_fleet_routes(server, impl_->ctx);
}

ApiServer::~ApiServer() { stop(); }

bool ApiServer::uses_tls() const { return impl_->options.uses_tls(); }

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
  impl_->listener_done = false;
  impl_->listener = std::thread([&server, &done = impl_->listener_done] {
    server.listen_after_bind();
    done = true;
  });
  spdlog::info("control API on {}://{}:{} ({})", o.uses_tls() ? "https" : "http", o.host, port,
               impl_->ctx.access.tokens.empty()     ? "no token: loopback only"
               : impl_->ctx.access.reads_need_token ? "bearer token required for every request"
                                                    : "bearer token required for changes");
  return port;
}

void ApiServer::stop() {
  if (!impl_) return;
  impl_->ctx.hub.close();  // ends live streams, whose threads the server joins
  if (impl_->listener.joinable()) {
    // cpp-httplib's stop() does nothing until the listening thread has marked the server
    // running, and that thread would then accept forever: a SIGTERM in the first moments after
    // start hung calstandd in join (found under AddressSanitizer, which slows the thread's
    // start). So wait until it runs, or has already returned, before stopping it.
    while (!impl_->server.is_running() && !impl_->listener_done) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    impl_->server.stop();
    impl_->listener.join();
  } else {
    impl_->server.stop();
  }
}

}  // namespace calstand::daemon::api

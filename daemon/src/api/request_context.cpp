#include "request_context.hpp"

namespace calstand::daemon::api {
namespace {

constexpr const char* kTokenParam = "access_token";

}  // namespace

std::string presented_token(const httplib::Request& req) {
  const std::string header = req.get_header_value("Authorization");  // by value: keep it
  if (const std::string_view bearer = bearer_of(header); !bearer.empty()) {
    return std::string(bearer);
  }
  if ((req.method == "GET" || req.method == "HEAD") && req.has_param(kTokenParam)) {
    return req.get_param_value(kTokenParam);
  }
  return {};
}

const NamedToken* caller_token(const RouteContext& ctx, const httplib::Request& req) {
  // Matched again rather than handed over from the access check: httplib's Request has no
  // place for it, and comparing a few short secrets costs nothing next to a request.
  return ctx.access.match(presented_token(req));
}

std::string who_of(const RouteContext& ctx, const httplib::Request& req) {
  const NamedToken* token = caller_token(ctx, req);
  return operator_name(req.get_header_value("X-Calstand-Operator"), req.remote_addr,
                       token ? std::string_view(token->name) : std::string_view());
}

}  // namespace calstand::daemon::api

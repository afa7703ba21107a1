#pragma once

// Who sent a request, for the route handlers: the one place that reads the credentials of a
// request (the access check before routing and every handler that records who acted).
//
// A handler that records an action writes `who_of(ctx, req)` where it records who asked, e.g.
// `ctx.service.abort(id, reason, who_of(ctx, req))`; it never reads the Authorization header
// itself. Whether the request was allowed at all is decided before any handler runs
// (api_server.cpp, AccessPolicy).

// clang-format off
#include <Eigen/Core>  // before httplib.h: its <resolv.h> defines a macro `_res`, a name Eigen uses
#include <httplib.h>
// clang-format on
#include <string>

#include "daemon/api/access.hpp"
#include "routes.hpp"

namespace calstand::daemon::api {

/// The bearer token a request presents: `Authorization: Bearer TOKEN`, or for a GET or HEAD
/// only the query parameter `access_token` (a browser's EventSource and the links the console
/// opens cannot set a header; a request that acts never takes it, so a link cannot act).
/// Empty when it presents none.
std::string presented_token(const httplib::Request& req);

/// The token that vouched for the request; nullptr when it presented none the daemon knows
/// (on loopback without tokens, or a read that needed none).
const NamedToken* caller_token(const RouteContext& ctx, const httplib::Request& req);

/// Who asked, for the records (events, queue rows, exit reasons): the `X-Calstand-Operator`
/// header and the client address, and the name of the token that vouched for the request,
/// as operator_name() writes them: `alice@10.0.0.7 (token lab-op)`.
std::string who_of(const RouteContext& ctx, const httplib::Request& req);

}  // namespace calstand::daemon::api

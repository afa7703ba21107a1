#pragma once

// The API's routes, by resource; api_server.cpp registers them.
#include <Eigen/Core>  // before httplib.h: its <resolv.h> defines a macro `_res`, a name Eigen uses
#include <httplib.h>

#include <string>

#include "daemon/service/event_hub.hpp"
#include "daemon/service/run_service.hpp"

namespace calstand::daemon::api {

/// What every handler needs. Handlers open their own database connection (SQLite connections
/// are not shared between threads).
struct RouteContext {
  service::RunService& service;
  service::EventHub& hub;
  std::string db_path;
};

/// /runs, /runs/{id}, /runs/{id}/steps|events|export, /runs/{id}/pause|resume|abort.
void register_run_routes(httplib::Server& server, const RouteContext& ctx);
/// /station, /calibrations/{id}, /events (server-sent events).
void register_station_routes(httplib::Server& server, const RouteContext& ctx);

}  // namespace calstand::daemon::api

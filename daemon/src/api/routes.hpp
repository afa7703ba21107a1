#pragma once

// The API's routes, by resource; api_server.cpp registers them.

// clang-format off
#include <Eigen/Core>  // before httplib.h: its <resolv.h> defines a macro `_res`, a name Eigen uses
#include <httplib.h>
// clang-format on
#include <atomic>
#include <functional>
#include <optional>
#include <string>

#include "daemon/api/access.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/run_service.hpp"
#include "fleet/central_address.hpp"

namespace calstand::daemon::api {

/// What every handler needs. Handlers open their own database connection (SQLite connections
/// are not shared between threads).
struct RouteContext {
  service::RunService& service;
  service::EventHub& hub;
  std::string db_path;
  /// Live streams (GET /events) open at most at once: each holds a connection thread for as
  /// long as it lasts, and the rest must stay free for requests (an operator's abort).
  int max_streams = 8;
  mutable std::atomic<int> open_streams{0};
  /// An export is being written (one at a time: each writes the run's CSV to disk first).
  mutable std::atomic<bool> exporting{false};
  /// Who may do what (set before the server starts; read-only afterwards). Handlers learn who
  /// asked from request_context.hpp, never from the request's headers themselves.
  AccessPolicy access{};
  /// The fleet's central database shown under /fleet, or none (ApiOptions::fleet).
  std::optional<fleet::CentralAddress> fleet{};
  /// The fleet publisher's state (ApiOptions::publish_status), or empty.
  std::function<nlohmann::json()> publish_status{};
};

/// /runs, /runs/{id}, /runs/{id}/steps|events|export, /runs/{id}/pause|resume|abort|skip.
void register_run_routes(httplib::Server& server, const RouteContext& ctx);
/// /station, /station/publish, /calibrations/{id}, /events (server-sent events).
void register_station_routes(httplib::Server& server, const RouteContext& ctx);
/// /procedures (the library with its parameters) and /plan (a plan preview, nothing queued).
void register_procedure_routes(httplib::Server& server, const RouteContext& ctx);
/// The web console: / and /console/FILE (files embedded at build time).
void register_console_routes(httplib::Server& server, const RouteContext& ctx);
/// /catalogue, /runs/{id}/fits|diagnose|history|report|calibrations|series (routes_analysis.cpp).
void register_analysis_routes(httplib::Server& server, const RouteContext& ctx);
/// The factory line: /lot, /units/{serial}/calibrations, /calibrations/{id}/certificate
/// (routes_factory.cpp).
void register_factory_routes(httplib::Server& server, const RouteContext& ctx);
/// The fleet's central database, read-only: /fleet (stations), /fleet/runs, /fleet/units,
/// /fleet/calibrations, /fleet/parameters (routes_fleet.cpp).
void register_fleet_routes(httplib::Server& server, const RouteContext& ctx);

}  // namespace calstand::daemon::api

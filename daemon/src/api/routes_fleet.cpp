// The fleet's central database, read-only (issue 19): what `calstand fleet` answers, for the
// console's fleet page. calstandd --fleet URL names the database (a calstand_reader role, by
// docs/fleet.md); every request connects anew, so a central server restarted in between is
// simply reached again, and one that is down is a 503 naming it, not a daemon fault.
#include <fmt/format.h>

#include "fleet/central_error.hpp"
#include "fleet/fleet_queries.hpp"
#include "http_util.hpp"
#include "routes.hpp"

namespace calstand::daemon::api {
namespace {

fleet::FleetFilter filter_of(const httplib::Request& req) {
  fleet::FleetFilter filter;
  if (req.has_param("station")) filter.station = req.get_param_value("station");
  if (req.has_param("serial")) filter.serial = req.get_param_value("serial");
  if (req.has_param("since")) filter.since_utc = req.get_param_value("since");
  // The date is the request's fault, whatever the central database holds.
  try {
    filter.validate();
  } catch (const core::InputError& e) {
    throw BadRequest(400, "?since", e.what());
  }
  return filter;
}

using Query = nlohmann::json (*)(pqxx::connection&, const fleet::FleetFilter&);

httplib::Server::Handler fleet_route(const RouteContext& ctx, Query query) {
  return guarded([&ctx, query](const httplib::Request& req, httplib::Response& res) {
    if (!ctx.fleet) {
      throw BadRequest(404, req.path,
                       "this calstandd shows no fleet: start it with --fleet postgresql://...");
    }
    const fleet::FleetFilter filter = filter_of(req);
    try {
      auto connection = fleet::connect_central(*ctx.fleet);
      send_json(res, 200, query(*connection, filter));
    } catch (const fleet::CentralError& e) {
      throw BadRequest(503, ctx.fleet->display, e.what());
    }
  });
}

}  // namespace

void register_fleet_routes(httplib::Server& server, const RouteContext& ctx) {
  server.Get("/fleet", fleet_route(ctx, fleet::fleet_stations));
  server.Get("/fleet/runs", fleet_route(ctx, fleet::fleet_runs));
  server.Get("/fleet/units", fleet_route(ctx, fleet::fleet_units));
  server.Get("/fleet/calibrations", fleet_route(ctx, fleet::fleet_calibrations));
  server.Get("/fleet/parameters", fleet_route(ctx, fleet::fleet_parameters));
}

}  // namespace calstand::daemon::api

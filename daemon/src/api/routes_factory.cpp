// The factory line (issue 17): /lot, /units/{serial}/calibrations and
// /calibrations/{id}/certificate. Each handler calls the analysis library as `calstand lot`,
// `calibrations` and `certificate` do, so that the answers are the command line's.
#include <fmt/format.h>

#include "core/error.hpp"
#include "factory/certificate.hpp"
#include "factory/lot.hpp"
#include "factory/unit_records.hpp"
#include "http_util.hpp"
#include "routes.hpp"
#include "store/calibrations.hpp"
#include "store/database.hpp"

namespace calstand::daemon::api {

void register_factory_routes(httplib::Server& server, const RouteContext& ctx) {
  server.Get("/lot", guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
               const std::string since = req.has_param("since") ? req.get_param_value("since") : "";
               // Checked before the database is opened: a typo is the request's fault, whatever
               // the database holds.
               analysis::check_lot_since(since, "?since");
               store::Database db(ctx.db_path);
               send_json(res, 200, analysis::to_json(analysis::lot_statistics(db, since)));
             }));

  // Any serial, '/' included (sent as %2F: the path is matched decoded). A serial nobody
  // calibrated has no records: an empty list, as `calstand calibrations --serial` prints.
  server.Get(R"(/units/(.+)/calibrations)",
             guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
               const std::string serial = req.matches[1].str();
               store::Database db(ctx.db_path);
               send_json(res, 200,
                         analysis::unit_records_json(serial, analysis::unit_records(db, serial)));
             }));

  // The page `calstand certificate --out FILE.html` writes. A PDF stays the command line's
  // (headless Chromium on the station for every request would be a heavy answer to a GET).
  server.Get(R"(/calibrations/(\d+)/certificate)",
             guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
               const std::int64_t id = id_from_path(req);
               store::Database db(ctx.db_path);
               try {
                 store::load_calibration(db, id);
               } catch (const core::InputError&) {
                 throw BadRequest(404, fmt::format("/calibrations/{}", id),
                                  fmt::format("no calibration {}", id));
               }
               std::string page;
               try {
                 page = analysis::certificate_html(analysis::certificate_data(db, id));
               } catch (const core::InputError& e) {
                 // The station lacks the plotter: not the request's fault.
                 if (e.where() == "gnuplot") throw BadRequest(503, e.where(), e.what());
                 throw;
               }
               res.status = 200;
               res.set_content(page, "text/html; charset=utf-8");
             }));
}

}  // namespace calstand::daemon::api

// /runs: submit, list, one run's status, steps, events and export; operator actions.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <limits>

#include "core/error.hpp"
#include "daemon/api/export_archive.hpp"
#include "daemon/api/run_request.hpp"
#include "http_util.hpp"
#include "request_context.hpp"
#include "routes.hpp"
#include "store/database.hpp"
#include "store/run_json.hpp"
#include "store/run_store.hpp"

namespace calstand::daemon::api {
namespace {

// GET /runs pages: the default and the most one answer holds.
constexpr std::int64_t kDefaultRunsPage = 100;
constexpr std::int64_t kMaxRunsPage = 1000;

store::RunRecord load_run_or_404(store::RunStore& runs, std::int64_t id) {
  try {
    return runs.load_run(id);
  } catch (const core::InputError&) {
    throw BadRequest(404, fmt::format("/runs/{}", id), fmt::format("no run {}", id));
  }
}

// The run of a /runs/{id}... request, read on a connection of its own; 404 when there is none.
store::RunRecord run_of(const RouteContext& ctx, const httplib::Request& req) {
  store::Database db(ctx.db_path);
  store::RunStore runs(db);
  return load_run_or_404(runs, id_from_path(req));
}

// Operator actions on an unknown run answer 404 (the service's own check would say 400).
void require_run(const RouteContext& ctx, std::int64_t id) {
  store::Database db(ctx.db_path);
  store::RunStore runs(db);
  load_run_or_404(runs, id);
}

// The optional `reason` of an action body (recorded with the action), at most 500 characters.
std::string reason_field(const nlohmann::json& body) {
  if (!body.is_object() || !body.contains("reason")) return "operator request";
  if (!body["reason"].is_string()) throw BadRequest(400, "body.reason", "must be a string");
  return body["reason"].get<std::string>().substr(0, 500);
}

// GET /runs/{id}: the stored summary, with the live position while the run is on the station.
nlohmann::json run_status_json(const store::RunRecord& record, const service::LiveSnapshot& live) {
  nlohmann::json j = store::to_json(record.summary);
  j["parameters"] = record.parameters;
  j["units"] = store::units_json(record.units);
  const auto total = record.summary.steps_total;
  j["progress"] = total == 0
                      ? 0.0
                      : static_cast<double>(record.summary.steps_done) / static_cast<double>(total);
  j["held"] = live.held == record.summary.id;
  if (live.run == record.summary.id) {
    const Progress& p = live.progress;
    j["live"] = {{"state", std::string(to_string(p.state))},
                 {"phase", p.phase},
                 {"station_time_s", p.station_time_s},
                 {"eta_s", p.eta_s}};
    j["current_step"] = {{"index", p.step}, {"label", p.label}};
    j["eta_s"] = p.eta_s;
  } else {
    j["eta_s"] = nullptr;
    for (const auto& s : record.steps) {
      if (s.status != store::StepStatus::kCompleted && s.status != store::StepStatus::kSkipped) {
        j["current_step"] = {{"index", s.index}, {"label", s.label}};
        break;
      }
    }
    if (!j.contains("current_step")) j["current_step"] = nullptr;
  }
  return j;
}

}  // namespace

void register_run_routes(httplib::Server& server, const RouteContext& ctx) {
  server.Post("/runs", guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
                const RunRequest request = parse_run_request(parse_json_body(req));
                const std::int64_t id = ctx.service.submit(request.procedure, request.overrides,
                                                           who_of(ctx, req), request.units);
                res.set_header("Location", fmt::format("/runs/{}", id));
                send_json(res, 201, {{"id", id}});
              }));

  // One page of runs, newest first; a full page links the next (years of a factory station's
  // runs are not one answer).
  server.Get(
      "/runs", guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
        const auto limit = int_param(req, "limit", 1, kMaxRunsPage).value_or(kDefaultRunsPage);
        const auto before = int_param(req, "before", 1, std::numeric_limits<std::int64_t>::max());
        store::Database db(ctx.db_path);
        auto page = store::RunStore(db).list_runs(static_cast<std::size_t>(limit) + 1, before);
        if (page.size() > static_cast<std::size_t>(limit)) {
          page.pop_back();
          res.set_header("Link", fmt::format("</runs?limit={}&before={}>; rel=\"next\"", limit,
                                             page.back().id));
        }
        nlohmann::json out = nlohmann::json::array();
        for (const auto& s : page) out.push_back(store::to_json(s));
        send_json(res, 200, out);
      }));

  server.Get(R"(/runs/(\d+))", guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
               const store::RunRecord record = run_of(ctx, req);
               send_json(res, 200, run_status_json(record, ctx.service.snapshot()));
             }));

  server.Get(R"(/runs/(\d+)/steps)",
             guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
               const store::RunRecord record = run_of(ctx, req);
               nlohmann::json out = nlohmann::json::array();
               for (const auto& s : record.steps) out.push_back(store::to_json(s));
               send_json(res, 200, out);
             }));

  server.Get(R"(/runs/(\d+)/events)",
             guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
               const store::RunRecord record = run_of(ctx, req);
               nlohmann::json out = nlohmann::json::array();
               for (const auto& e : record.events) out.push_back(store::to_json(e));
               send_json(res, 200, out);
             }));

  server.Get(
      R"(/runs/(\d+)/export)", guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
        const std::int64_t id = id_from_path(req);
        // One export at a time: each writes the run's CSV to a temporary file before sending it.
        if (ctx.exporting.exchange(true)) {
          res.set_header("Retry-After", "10");
          throw BadRequest(503, req.path, "another export is being prepared; try again shortly");
        }
        struct Done {
          std::atomic<bool>& flag;
          ~Done() { flag = false; }
        } done{ctx.exporting};
        store::Database db(ctx.db_path);
        store::RunStore runs(db);
        load_run_or_404(runs, id);
        const std::string device = req.has_param("device") ? req.get_param_value("device") : "";
        // Sent piece by piece from a temporary folder beside the database (not /tmp, which may be
        // in memory), removed when the response goes. Any byte range can be asked for.
        const auto db_dir = std::filesystem::absolute(ctx.db_path).parent_path();
        auto archive = std::make_shared<ExportArchive>(db, id, device, db_dir);
        // No status set here: httplib answers 200, or 206 for a range.
        res.set_header("Content-Disposition",
                       fmt::format("attachment; filename=\"run-{}.tar\"", id));
        res.set_content_provider(
            static_cast<std::size_t>(archive->size()), "application/x-tar",
            [archive, id](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
              // No exception may leave a content provider: httplib's writer would terminate.
              try {
                const std::string chunk =
                    archive->read_at(offset, std::min(length, ExportArchive::kChunkBytes));
                return !chunk.empty() && sink.write(chunk.data(), chunk.size());
              } catch (const std::exception& e) {
                spdlog::error("GET /runs/{}/export: {}", id, e.what());
                return false;
              }
            });
      }));

  server.Post(
      R"(/runs/(\d+)/pause)", guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
        const std::int64_t id = id_from_path(req);
        require_run(ctx, id);
        const auto body = parse_json_body(req, nlohmann::json::object());
        bool immediate = false;
        if (body.is_object() && body.contains("immediate")) {
          if (!body["immediate"].is_boolean())
            throw BadRequest(400, "body.immediate", "must be true or false");
          immediate = body["immediate"].get<bool>();
        }
        ctx.service.pause(id, immediate, who_of(ctx, req));
        send_json(
            res, 202,
            {{"id", id}, {"requested", immediate ? "pause at once" : "pause at step boundary"}});
      }));

  server.Post(R"(/runs/(\d+)/resume)",
              guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
                const std::int64_t id = id_from_path(req);
                require_run(ctx, id);
                ctx.service.resume(id, who_of(ctx, req));
                send_json(res, 202, {{"id", id}, {"requested", "resume"}});
              }));

  server.Post(R"(/runs/(\d+)/abort)",
              guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
                const std::int64_t id = id_from_path(req);
                require_run(ctx, id);
                const auto body = parse_json_body(req, nlohmann::json::object());
                ctx.service.abort(id, reason_field(body), who_of(ctx, req));
                send_json(res, 202, {{"id", id}, {"requested", "abort"}});
              }));

  server.Post(R"(/runs/(\d+)/skip)",
              guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
                const std::int64_t id = id_from_path(req);
                require_run(ctx, id);
                const auto body = parse_json_body(req, nlohmann::json::object());
                const std::string reason = reason_field(body);
                std::optional<std::size_t> step;
                if (body.is_object() && body.contains("step")) {
                  if (!body["step"].is_number_unsigned())
                    throw BadRequest(400, "body.step", "must be a step index (0, 1, ...)");
                  step = body["step"].get<std::size_t>();
                }
                ctx.service.skip(id, step, reason, who_of(ctx, req));
                nlohmann::json answer = {{"id", id}, {"requested", "skip"}};
                if (step) answer["step"] = *step;
                send_json(res, 202, answer);
              }));
}

}  // namespace calstand::daemon::api

// The model-against-measurement loop (issue 14): /catalogue, /runs/{id}/fits|diagnose|history|
// report|calibrations|series|acceptance. Every handler calls the analysis library as `calstand
// fit`, `diagnose`, `history`, `report` and `accept` do, so that the answers are the command
// line's.
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>

#include "analysis/catalogue.hpp"
#include "analysis/fit_history.hpp"
#include "analysis/fit_request.hpp"
#include "analysis/run_model.hpp"
#include "analysis/run_series.hpp"
#include "analysis/table_free_diagnose.hpp"
#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "factory/accept_run.hpp"
#include "factory/acceptance_spec.hpp"
#include "http_util.hpp"
#include "render/gnuplot_svg.hpp"
#include "report/report_html.hpp"
#include "request_context.hpp"
#include "routes.hpp"
#include "store/calibrations.hpp"
#include "store/database.hpp"
#include "store/fit_history.hpp"
#include "store/run_store.hpp"

namespace calstand::daemon::api {
namespace {

// Buckets of a /series answer: the default and the most one answer holds (a plot is at most a
// few thousand pixels wide; min, max and mean per bucket triple the numbers).
constexpr std::int64_t kDefaultSeriesPoints = 2000;
constexpr std::int64_t kMaxSeriesPoints = 100000;

std::string run_path(std::int64_t id) { return fmt::format("/runs/{}", id); }

void require_run_or_404(store::Database& db, std::int64_t id) {
  try {
    store::RunStore(db).run_status(id);  // throws for an unknown run
  } catch (const core::InputError&) {
    throw BadRequest(404, run_path(id), fmt::format("no run {}", id));
  }
}

std::vector<std::string> string_list(const nlohmann::json& body, const char* field) {
  std::vector<std::string> out;
  if (!body.contains(field) || body[field].is_null()) return out;
  const std::string where = fmt::format("body.{}", field);
  if (!body[field].is_array()) throw BadRequest(400, where, "must be an array of strings");
  for (std::size_t i = 0; i < body[field].size(); ++i) {
    if (!body[field][i].is_string()) {
      throw BadRequest(400, fmt::format("{}[{}]", where, i), "must be a string");
    }
    out.push_back(body[field][i].get<std::string>());
  }
  return out;
}

std::string string_field(const nlohmann::json& body, const char* field,
                         const std::string& fallback) {
  if (!body.contains(field) || body[field].is_null()) return fallback;
  if (!body[field].is_string())
    throw BadRequest(400, fmt::format("body.{}", field), "must be a string");
  return body[field].get<std::string>();
}

// The body of POST /runs/{id}/fits and /diagnose as a request of the analysis library: the
// fields of `calstand fit` (model and custom as lists, the default model when none given).
analysis::FitRequest fit_request_of(const httplib::Request& req, const std::string& command) {
  const nlohmann::json body = parse_json_body(req, nlohmann::json::object());
  if (!body.is_object()) throw BadRequest(400, "body", "must be a JSON object");
  for (const auto& [key, value] : body.items()) {
    if (key != "model" && key != "custom" && key != "device" && key != "sensor" &&
        key != "white_noise" && key != "noise_run") {
      throw BadRequest(
          400, "body." + key,
          "unknown field (known: model, custom, device, sensor, white_noise, noise_run)");
    }
  }
  analysis::FitRequest request;
  try {
    request.model =
        analysis::model_from_lists(string_list(body, "model"), string_list(body, "custom"));
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    const std::string why = what.substr(std::min(what.size(), e.where().size() + 2));
    throw BadRequest(400, "body." + e.where(), why);
  }
  request.device = string_field(body, "device", "");
  request.sensor = string_field(body, "sensor", "both");
  analysis::parse_sensor_rows(request.sensor, "body.sensor");
  if (body.contains("white_noise") && !body["white_noise"].is_null()) {
    if (!body["white_noise"].is_boolean())
      throw BadRequest(400, "body.white_noise", "must be true or false");
    request.white_noise = body["white_noise"].get<bool>();
  }
  if (body.contains("noise_run") && !body["noise_run"].is_null()) {
    const nlohmann::json& v = body["noise_run"];
    if (!v.is_number_integer() || v.get<std::int64_t>() < 1)
      throw BadRequest(400, "body.noise_run", "must be a run id (a positive integer)");
    request.noise_run = v.get<std::int64_t>();
  }
  request.history_command = command;
  return request;
}

// The request of a run without a table: the model's optional terms (a term such a run cannot
// fit is a 400 naming it), the static poses as the detector finds them; `sensor` and
// `white_noise` do not apply (both sensors are fitted, each against its own noise), and a
// `noise_run` is refused (the poses are weighed by their own pose noise).
analysis::TableFreeFitRequest table_free_request_of(const analysis::FitRequest& fit) {
  if (fit.noise_run) {
    throw BadRequest(400, "body.noise_run",
                     "the run was recorded without a table: its poses are weighed by their own "
                     "noise, not a static run's");
  }
  analysis::TableFreeFitRequest request;
  try {
    request = analysis::table_free_request(fit.model, {});
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    throw BadRequest(400, "body.model", what.substr(std::min(what.size(), e.where().size() + 2)));
  }
  request.device = fit.device;
  request.history_command = fit.history_command;
  return request;
}

// Runs `fn` mapping the analysis library's run errors to answers: an unknown run 404, a run
// with nothing to fit 409 (it is still recording, or recorded no samples).
template <typename Fn>
auto on_run(std::int64_t id, Fn&& fn) {
  try {
    return fn();
  } catch (const analysis::RunNotFound&) {
    throw BadRequest(404, run_path(id), fmt::format("no run {}", id));
  } catch (const analysis::NothingToFit& e) {
    throw BadRequest(409, e.where(), e.what());
  }
}

std::optional<double> double_param(const httplib::Request& req, const std::string& name) {
  if (!req.has_param(name)) return std::nullopt;
  const std::string text = req.get_param_value(name);
  if (text.empty()) return std::nullopt;
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(v)) {
    throw BadRequest(400, "?" + name, fmt::format("expected a number of seconds, got '{}'", text));
  }
  return v;
}

// A fit or a diagnosis asked for through the API is an operator action (it writes the run's
// history): recorded in the run's events with who asked and the model of the answer.
void record_fit_action(const RouteContext& ctx, const httplib::Request& req, std::int64_t id,
                       const std::string& command, const nlohmann::json& answer) {
  const nlohmann::json* model = nullptr;
  if (answer.contains("model")) {
    model = &answer["model"];
  } else if (answer.contains("fit") && answer["fit"].contains("model")) {
    model = &answer["fit"]["model"];
  }
  ctx.service.record_action(
      id, who_of(ctx, req),
      fmt::format("{} requested; model {}", command,
                  model ? model->dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)
                        : std::string("(none)")));
}

std::string text_param(const httplib::Request& req, const std::string& name,
                       const std::string& fallback) {
  return req.has_param(name) ? req.get_param_value(name) : fallback;
}

}  // namespace

void register_analysis_routes(httplib::Server& server, const RouteContext& ctx) {
  server.Get("/catalogue", guarded([](const httplib::Request&, httplib::Response& res) {
               static const nlohmann::json catalogue = analysis::catalogue_json();
               send_json(res, 200, catalogue);
             }));

  server.Post(
      R"(/runs/(\d+)/fits)", guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
        const std::int64_t id = id_from_path(req);
        const analysis::FitRequest request = fit_request_of(req, "fit");
        store::Database db(ctx.db_path);
        if (on_run(id, [&] { return analysis::needs_table_free_fit(db, id); })) {
          const analysis::TableFreeFit fit = on_run(
              id, [&] { return analysis::table_free_fit(db, id, table_free_request_of(request)); });
          const nlohmann::json out = analysis::to_json(fit);
          record_fit_action(ctx, req, id, "fit", out);
          send_json(res, 200, out);
          return;
        }
        const analysis::FitOutcome outcome =
            on_run(id, [&] { return analysis::fit_request(db, id, request); });
        nlohmann::json out = analysis::to_json(outcome);
        out["history_id"] = *outcome.history_id;
        record_fit_action(ctx, req, id, "fit", out);
        send_json(res, 200, out);
      }));

  server.Post(R"(/runs/(\d+)/diagnose)",
              guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
                const std::int64_t id = id_from_path(req);
                const analysis::FitRequest request = fit_request_of(req, "diagnose");
                store::Database db(ctx.db_path);
                if (on_run(id, [&] { return analysis::needs_table_free_fit(db, id); })) {
                  const analysis::TableFreeDiagnosis d = on_run(id, [&] {
                    return analysis::diagnose_table_free(db, id, table_free_request_of(request));
                  });
                  const nlohmann::json out = analysis::to_json(d);
                  record_fit_action(ctx, req, id, "diagnose", out);
                  send_json(res, 200, out);
                  return;
                }
                const analysis::DiagnoseOutcome outcome =
                    on_run(id, [&] { return analysis::diagnose_request(db, id, request); });
                const nlohmann::json out = analysis::to_json(outcome);
                record_fit_action(ctx, req, id, "diagnose", out);
                send_json(res, 200, out);
              }));

  server.Get(R"(/runs/(\d+)/history)",
             guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
               const std::int64_t id = id_from_path(req);
               store::Database db(ctx.db_path);
               require_run_or_404(db, id);
               send_json(res, 200, analysis::history_to_json(store::fit_history(db, id)));
             }));

  server.Get(R"(/runs/(\d+)/report)",
             guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
               analysis::ReportRequest request;
               request.run = id_from_path(req);
               request.db = std::filesystem::path(ctx.db_path).filename().string();
               request.model = text_param(req, "model", analysis::kDefaultModel);
               for (std::size_t i = 0; i < req.get_param_value_count("custom"); ++i) {
                 request.customs.push_back(req.get_param_value("custom", i));
               }
               request.device = text_param(req, "device", "");
               request.sensor = text_param(req, "sensor", "both");
               request.noise_model = text_param(req, "noise_model", "true") != "false";
               analysis::parse_sensor_rows(request.sensor, "?sensor");
               store::Database db(ctx.db_path);
               std::string page;
               try {
                 page = on_run(request.run, [&] { return analysis::run_report_html(db, request); });
               } catch (const core::InputError& e) {
                 // The station lacks the plotter: not the request's fault.
                 if (e.where() == "gnuplot") throw BadRequest(503, e.where(), e.what());
                 throw;
               }
               res.status = 200;
               res.set_content(page, "text/html; charset=utf-8");
             }));

  server.Get(R"(/runs/(\d+)/calibrations)",
             guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
               const std::int64_t id = id_from_path(req);
               store::Database db(ctx.db_path);
               require_run_or_404(db, id);
               nlohmann::json out = nlohmann::json::array();
               for (const auto& c : store::calibrations_of_run(db, id)) {
                 const nlohmann::json* chi2_dof = nullptr;
                 if (c.record.contains("fit") && c.record["fit"].contains("chi2_dof"))
                   chi2_dof = &c.record["fit"]["chi2_dof"];
                 out.push_back({{"id", c.id},
                                {"run", c.run},
                                {"imu", c.imu},
                                {"model", c.model},
                                {"created_utc", c.created_utc},
                                {"chi2_dof", chi2_dof ? *chi2_dof : nlohmann::json()},
                                {"href", fmt::format("/calibrations/{}", c.id)}});
               }
               send_json(res, 200, out);
             }));

  // The body is the specification itself, as `calstand accept --spec` reads it from a file; its
  // sha256 is of the body's bytes.
  server.Post(
      R"(/runs/(\d+)/acceptance)",
      guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
        const std::int64_t id = id_from_path(req);
        parse_json_body(req, std::nullopt);  // the depth limit, before the schema's own parse
        analysis::AcceptanceSpec spec;
        try {
          spec = analysis::parse_acceptance_spec(req.body, "body");
        } catch (const core::SchemaError& e) {
          nlohmann::json violations = nlohmann::json::array();
          for (const auto& v : e.violations())
            violations.push_back({{"path", v.path}, {"message", v.message}});
          send_json(
              res, 400,
              {{"error", "invalid specification"}, {"where", "body"}, {"violations", violations}});
          return;
        }
        analysis::AcceptRequest request;
        request.run = id;
        request.device = text_param(req, "device", "");
        request.validation_run =
            int_param(req, "validation_run", 1, std::numeric_limits<std::int64_t>::max());
        store::Database db(ctx.db_path);
        analysis::AcceptanceOutcome outcome;
        try {
          outcome = analysis::accept_run(db, spec, request);
        } catch (const analysis::RunNotFound& e) {
          throw BadRequest(404, e.where(), e.what());
        } catch (const analysis::NoCalibrationRecord& e) {
          throw BadRequest(409, e.where(), e.what());
        } catch (const analysis::NothingToFit& e) {
          throw BadRequest(409, e.where(), e.what());
        }
        analysis::store_acceptances(db, outcome);
        ctx.service.record_action(
            id, who_of(ctx, req),
            fmt::format("acceptance against \"{}\" (sha256 {}): {}", spec.name,
                        spec.sha256.substr(0, 12), analysis::to_string(outcome.verdict)));
        send_json(res, 200, analysis::to_json(outcome));
      }));

  server.Get(
      R"(/runs/(\d+)/series)", guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
        const std::int64_t id = id_from_path(req);
        if (!req.has_param("signal"))
          throw BadRequest(400, "?signal", "required (e.g. ?signal=gz)");
        analysis::SeriesRequest request;
        request.signal = req.get_param_value("signal");
        request.device = text_param(req, "device", "");
        request.max_points = static_cast<std::size_t>(
            int_param(req, "max_points", 2, kMaxSeriesPoints).value_or(kDefaultSeriesPoints));
        if (const auto from = double_param(req, "from_s")) request.from_s = *from;
        if (const auto to = double_param(req, "to_s")) request.to_s = *to;
        store::Database db(ctx.db_path);
        analysis::RunSeries series;
        try {
          series = on_run(id, [&] { return analysis::run_series(db, id, request); });
        } catch (const core::InputError& e) {
          // The library names its own fields; on the API they are query parameters.
          const bool field =
              e.where() == "signal" || e.where() == "max_points" || e.where() == "from_s/to_s";
          throw BadRequest(400, field ? "?" + e.where() : e.where(), e.what());
        }
        send_json(res, 200, analysis::to_json(series));
      }));
}

}  // namespace calstand::daemon::api

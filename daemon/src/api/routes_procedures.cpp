// /procedures (the compiled-in library and its parameters) and /plan (what a submission would
// run, its duration, envelope and every rule it breaks; nothing is queued): the console's
// submit form shows the plan before the operator queues it.
#include "daemon/api/run_request.hpp"
#include "http_util.hpp"
#include "procedures/library.hpp"
#include "procedures/plan.hpp"
#include "routes.hpp"

namespace calstand::daemon::api {
namespace {

nlohmann::json parameter_spec_json(const procedures::ParameterSpec& spec) {
  nlohmann::json j = {{"name", spec.name},
                      {"type", std::string(procedures::to_string(spec.type))},
                      {"default", spec.default_value},
                      {"description", spec.description}};
  j["min"] = spec.min ? nlohmann::json(*spec.min) : nlohmann::json();
  j["max"] = spec.max ? nlohmann::json(*spec.max) : nlohmann::json();
  return j;
}

}  // namespace

void register_procedure_routes(httplib::Server& server, const RouteContext& ctx) {
  server.Get(
      "/procedures", guarded([](const httplib::Request&, httplib::Response& res) {
        nlohmann::json out = nlohmann::json::array();
        for (const auto& name : procedures::library_names()) {
          const procedures::Procedure p = procedures::load_procedure(name);
          nlohmann::json params = nlohmann::json::array();
          for (const auto& [_, spec] : p.parameter_specs)
            params.push_back(parameter_spec_json(spec));
          out.push_back({{"name", name}, {"description", p.description}, {"parameters", params}});
        }
        send_json(res, 200, out);
      }));

  // The body of POST /runs; the answer is `calstand plan --json` against the daemon's station,
  // violations included (200 either way: a plan that breaks rules is still an answer).
  server.Post("/plan", guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
                const RunRequest request = parse_run_request(parse_json_body(req));
                const procedures::Plan plan = procedures::make_plan(
                    request.procedure, ctx.service.options().station, request.overrides);
                send_json(res, 200, plan.to_json());
              }));
}

}  // namespace calstand::daemon::api

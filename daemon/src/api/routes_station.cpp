// /station, /calibrations/{id} and the live stream /events.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <memory>

#include "core/error.hpp"
#include "core/state_json.hpp"
#include "daemon/service/observed_journal.hpp"
#include "http_util.hpp"
#include "request_context.hpp"
#include "routes.hpp"
#include "store/calibrations.hpp"
#include "store/database.hpp"
#include "store/run_json.hpp"
#include "store/run_queue.hpp"
#include "store/run_store.hpp"
#include "wire/sse_encoder.hpp"

namespace calstand::daemon::api {
namespace {

// Station-wide events (an interlock closed between runs, ...) that GET /station shows.
constexpr std::size_t kStationEventsShown = 20;

// How long a stream waits for a message before sending a keep-alive comment: also how soon a
// closed client connection is noticed.
constexpr auto kKeepAlive = std::chrono::milliseconds(1000);

nlohmann::json station_json(const RouteContext& ctx) {
  const service::LiveSnapshot live = ctx.service.snapshot();
  nlohmann::json devices = nlohmann::json::array();
  for (const auto& d : live.devices) {
    devices.push_back({{"kind", d.kind},
                       {"name", d.name},
                       {"backend", d.backend},
                       {"state", d.state},
                       {"fault_counters", d.fault_counters}});
  }
  store::Database db(ctx.db_path);
  nlohmann::json queue = nlohmann::json::array();
  for (const auto& q : store::queued_runs(db)) {
    queue.push_back(
        {{"run", q.run}, {"submitted_utc", q.submitted_utc}, {"submitted_by", q.submitted_by}});
  }
  nlohmann::json events = nlohmann::json::array();
  for (const auto& e : store::RunStore(db).station_events(kStationEventsShown)) {
    events.push_back(store::to_json(e));
  }
  nlohmann::json j = {
      {"name", ctx.service.options().station.name},
      {"waiting", live.waiting ? nlohmann::json(*live.waiting) : nlohmann::json()},
      {"events", events},
      {"devices", devices},
      {"run", live.run ? nlohmann::json(*live.run) : nlohmann::json()},
      {"held", live.held ? nlohmann::json(*live.held) : nlohmann::json()},
      {"queue", queue},
      {"telemetry",
       {{"table", live.table ? core::to_json(*live.table) : nlohmann::json()},
        {"chamber", live.chamber ? core::to_json(*live.chamber) : nlohmann::json()}}}};
  if (live.run) {
    j["progress"] = {{"state", std::string(to_string(live.progress.state))},
                     {"step", live.progress.step},
                     {"steps", live.progress.steps},
                     {"label", live.progress.label},
                     {"phase", live.progress.phase},
                     {"station_time_s", live.progress.station_time_s},
                     {"eta_s", live.progress.eta_s}};
  }
  return j;
}

// A live stream's place among RouteContext::max_streams, given back when it is destroyed.
class StreamSlot {
 public:
  explicit StreamSlot(std::atomic<int>& open) : open_(open) {}
  ~StreamSlot() { open_.fetch_sub(1); }
  StreamSlot(const StreamSlot&) = delete;
  StreamSlot& operator=(const StreamSlot&) = delete;

 private:
  std::atomic<int>& open_;
};

// How long a reader waits before it reconnects after the stream broke [ms]: a daemon restart
// takes about a second, and browsers otherwise choose for themselves (3 s to 5 s).
constexpr unsigned kReconnectMs = 2000;

// One message; `id` empty for the greeting, which is a snapshot, not one of the hub's messages
// (a reader that reconnects names the last real message it saw).
std::string sse_message(const std::string& id, const std::string& type,
                        const nlohmann::json& data) {
  return wire::encode_sse_event(
      {type, data.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), id});
}

}  // namespace

void register_station_routes(httplib::Server& server, const RouteContext& ctx) {
  server.Get("/station", guarded([&ctx](const httplib::Request&, httplib::Response& res) {
               send_json(res, 200, station_json(ctx));
             }));

  // How publishing to the fleet's central database goes (calstandd --publish): a failure is
  // otherwise only in the log.
  server.Get("/station/publish",
             guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
               if (!ctx.publish_status) {
                 throw BadRequest(404, req.path,
                                  "this calstandd does not publish: start it with --publish");
               }
               send_json(res, 200, ctx.publish_status());
             }));

  // The operator's deliberate close of latched table interlocks, between runs (409 while a
  // run is on the station or when the controller refuses: the cause is still present).
  server.Post("/station/interlock/close",
              guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
                const std::string who = who_of(ctx, req);
                const auto closure = ctx.service.close_interlocks(who);
                if (!closure.result) throw BadRequest(409, req.path, closure.result.message);
                send_json(res, 200, {{"closed", closure.closed}, {"by", who}});
              }));

  server.Get(R"(/calibrations/(\d+))",
             guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
               const std::int64_t id = id_from_path(req);
               store::Database db(ctx.db_path);
               store::CalibrationRow row;
               try {
                 row = store::load_calibration(db, id);
               } catch (const core::InputError&) {
                 throw BadRequest(404, req.path, fmt::format("no calibration {}", id));
               }
               send_json(res, 200,
                         {{"id", row.id},
                          {"run", row.run},
                          {"imu", row.imu},
                          {"model", row.model},
                          {"created_utc", row.created_utc},
                          {"record", row.record}});
             }));

  // Server-sent events: first a "station" message with the whole status, then every message
  // the hub publishes (step, run, event, fault, telemetry), each with its id. A reader that
  // reconnects with Last-Event-ID first gets what it missed that the hub still keeps; when
  // messages were lost (too far behind, or no longer kept) a "gap" message says how many.
  server.Get(
      "/events", guarded([&ctx](const httplib::Request& req, httplib::Response& res) {
        if (ctx.open_streams.fetch_add(1) >= ctx.max_streams) {
          ctx.open_streams.fetch_sub(1);
          res.set_header("Retry-After", "5");
          throw BadRequest(503, "GET /events",
                           fmt::format("{} live streams are open already (the most this "
                                       "daemon serves at once); try again later",
                                       ctx.max_streams));
        }
        // The stream's slot is given back when its response goes away, however the stream ended.
        auto slot = std::make_shared<StreamSlot>(ctx.open_streams);
        std::uint64_t after = ctx.hub.last_seq();
        std::string restart_gap;
        if (req.has_header("Last-Event-ID")) {
          const std::string last_id = req.get_header_value("Last-Event-ID");
          if (const auto replay = ctx.hub.replay_after(last_id)) {
            after = replay->after_seq;
            if (replay->restarted) {
              restart_gap = sse_message("", "gap",
                                        {{"missed", nullptr},
                                         {"after_id", last_id},
                                         {"reason", "the daemon restarted since that message"}});
            }
          }
        }
        auto last_seq = std::make_shared<std::uint64_t>(after);
        auto greeting = std::make_shared<std::string>(
            wire::encode_sse_retry(kReconnectMs) + sse_message("", "station", station_json(ctx)) +
            restart_gap);
        res.set_header("Cache-Control", "no-cache");
        res.set_chunked_content_provider(
            "text/event-stream",
            [hub = &ctx.hub, last_seq, greeting, slot](std::size_t, httplib::DataSink& sink) {
              // No exception may leave a content provider: httplib's writer would terminate.
              try {
                if (!greeting->empty()) {
                  const std::string first = std::move(*greeting);
                  greeting->clear();
                  return sink.write(first.data(), first.size());
                }
                if (hub->closed()) {
                  sink.done();
                  return true;
                }
                const auto events = hub->wait_after(*last_seq, kKeepAlive);
                if (events.empty()) {
                  static const std::string kPing = wire::encode_sse_comment("keep-alive");
                  return sink.write(kPing.data(), kPing.size());
                }
                std::string chunk;
                if (events.front().seq > *last_seq + 1) {
                  chunk += sse_message("", "gap",
                                       {{"missed", events.front().seq - *last_seq - 1},
                                        {"after_id", hub->event_id(*last_seq)}});
                }
                for (const auto& e : events)
                  chunk += sse_message(hub->event_id(e.seq), e.type, e.data);
                *last_seq = events.back().seq;
                return sink.write(chunk.data(), chunk.size());
              } catch (const std::exception& e) {
                spdlog::error("GET /events: {}", e.what());
                return false;
              }
            });
      }));
}

}  // namespace calstand::daemon::api

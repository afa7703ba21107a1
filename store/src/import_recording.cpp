#include "store/import_recording.hpp"

#include <SQLiteCpp/Statement.h>
#include <SQLiteCpp/Transaction.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "batch_prefetch.hpp"
#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"
#include "core/site.hpp"
#include "import_format.hpp"
#include "sql_util.hpp"
#include "step_writer.hpp"
#include "store/hash.hpp"
#include "store/import_export.hpp"
#include "store/stamp.hpp"

namespace calstand::store {
namespace {

// The same factor as a /2 samples.csv in rad/s (import_format.cpp), so that a recording and
// its CSV give identical samples.
constexpr double kRecordingDegPerRad = 180.0 / std::numbers::pi;
// Intervals used for the nominal period, and an interval counted as a gap above this many
// periods.
constexpr std::size_t kPeriodIntervals = 1000;
constexpr double kGapPeriods = 1.5;

/// Gaps, out-of-order and repeated stamps of a stream of stamps, in constant memory: the
/// period is the median of the first kPeriodIntervals intervals. Intervals are taken from the
/// latest stamp so far, so that a stamp out of order counts once (and the interval over it as
/// a gap).
class StampCheck {
 public:
  explicit StampCheck(RecordingImportResult& r) : r_(r) {}

  void add(double t) {
    if (count_++ == 0) {
      r_.first_s = t;
      last_ = t;
      return;
    }
    const double dt = t - last_;
    last_ = std::max(last_, t);
    if (period_ > 0.0) {
      judge(dt, t);
    } else {
      pending_.emplace_back(dt, t);
      if (pending_.size() >= kPeriodIntervals) settle();
    }
  }

  void finish() {
    settle();
    r_.last_s = last_;
  }

 private:
  void settle() {
    if (period_ > 0.0 || pending_.empty()) return;
    std::vector<double> positive;
    for (const auto& [dt, t] : pending_) {
      if (dt > 0.0) positive.push_back(dt);
    }
    if (!positive.empty()) {
      std::nth_element(positive.begin(), positive.begin() + positive.size() / 2, positive.end());
      period_ = positive[positive.size() / 2];
    }
    r_.period_s = period_;
    for (const auto& [dt, t] : pending_) judge(dt, t);
    pending_.clear();
  }

  void judge(double dt, double t) {
    if (dt < 0.0) {
      ++r_.out_of_order;  // last_ stays the latest stamp
    } else if (dt == 0.0) {
      ++r_.duplicates;
    } else if (period_ > 0.0 && dt > kGapPeriods * period_) {
      ++r_.gaps;
      r_.gap_time_s += dt - period_;
      if (dt > r_.largest_gap_s) {
        r_.largest_gap_s = dt;
        r_.largest_gap_at_s = t;
      }
    }
  }

  RecordingImportResult& r_;
  std::uint64_t count_ = 0;
  double last_ = 0.0;
  double period_ = 0.0;
  std::vector<std::pair<double, double>> pending_;
};

std::string topic_line(const TopicInfo& t) {
  return fmt::format("{} ({}, {} messages, {:.4g} Hz)", t.name, t.type, t.count, t.rate_hz);
}

// Picks the topic: the one asked for, or the only IMU topic.
TopicInfo choose_topic(RecordingReader& reader, const std::string& wanted,
                       const std::filesystem::path& path, RecordingImportResult& result) {
  if (!wanted.empty()) {
    reader.select(wanted);
    TopicInfo t;
    t.name = wanted;
    return t;
  }
  result.topics = reader.topics();
  std::vector<TopicInfo> imu;
  for (const TopicInfo& t : result.topics) {
    if (t.imu) imu.push_back(t);
  }
  if (imu.size() == 1) {
    reader.select(imu.front().name);
    return imu.front();
  }
  std::string list;
  for (const TopicInfo& t : imu.empty() ? result.topics : imu) {
    list += "\n  " + topic_line(t);
  }
  if (imu.empty()) {
    throw core::InputError(
        path.string(),
        fmt::format("no IMU topic (sensor_msgs/msg/Imu in cdr, sensor_msgs/Imu in ros1); the "
                    "topics are:{}",
                    list.empty() ? std::string(" none") : list));
  }
  throw core::InputError(
      path.string(), fmt::format("{} IMU topics; choose one with --topic:{}", imu.size(), list));
}

void resolve_site(const RecordingImportOptions& o, RecordingImportResult& r) {
  if (o.latitude_deg.has_value() != o.height_m.has_value()) {
    throw core::InputError(o.latitude_deg ? "--height" : "--latitude",
                           "the site needs both --latitude and --height");
  }
  if (o.latitude_deg) {
    r.latitude_deg = *o.latitude_deg;
    r.height_m = *o.height_m;
    r.site_source = "given";
  } else {
    r.latitude_deg = kDefaultLatitudeDeg;
    r.height_m = kDefaultHeightM;
    r.site_source = fmt::format(
        "default: no site given, latitude {} deg and height {} m assumed (give --latitude and "
        "--height; the Earth rate and normal gravity depend on them)",
        kDefaultLatitudeDeg, kDefaultHeightM);
  }
  if (o.gravity_mps2) {
    r.gravity_mps2 = *o.gravity_mps2;
  } else {
    r.gravity_mps2 = core::normal_gravity(r.latitude_deg, r.height_m);
    if (o.latitude_deg) r.site_source = "given; gravity is the normal gravity there";
  }
}

nlohmann::ordered_json import_meta(const RecordingImportResult& r, double rate_hz) {
  nlohmann::ordered_json meta;
  meta["format"] = std::string(detail::kImportFormat2);
  meta["site"] = {
      {"latitude_deg", r.latitude_deg}, {"height_m", r.height_m}, {"gravity_mps2", r.gravity_mps2}};
  meta["sample_rate_hz"] = rate_hz;
  meta["units"] = {{"gyro", "rad/s"}, {"accel", "m/s^2"}, {"time", "s"}};
  return meta;
}

}  // namespace

nlohmann::ordered_json RecordingImportResult::to_json() const {
  nlohmann::ordered_json j;
  j["run"] = run;
  j["format"] = format;
  j["path"] = path;
  j["topic"] = {{"name", topic.name}, {"type", topic.type}, {"encoding", topic.encoding}};
  j["samples"] = samples;
  j["site"] = {{"latitude_deg", latitude_deg},
               {"height_m", height_m},
               {"gravity_mps2", gravity_mps2},
               {"source", site_source}};
  j["first_s"] = first_s;
  j["last_s"] = last_s;
  j["duration_s"] = last_s - first_s;
  j["rate_hz"] = rate_hz;
  j["gaps"] = {{"count", gaps},
               {"missing_s", gap_time_s},
               {"largest_s", largest_gap_s},
               {"largest_at_s", largest_gap_at_s}};
  j["out_of_order"] = out_of_order;
  j["duplicate_stamps"] = duplicates;
  if (!topics.empty()) {
    auto& list = j["topics"] = nlohmann::ordered_json::array();
    for (const TopicInfo& t : topics) {
      list.push_back({{"name", t.name},
                      {"type", t.type},
                      {"count", t.count},
                      {"rate_hz", t.rate_hz},
                      {"imu", t.imu}});
    }
  }
  return j;
}

RecordingImportResult import_recording(Database& db, const std::filesystem::path& path,
                                       const RecordingImportOptions& options) {
  RecordingImportResult result;
  result.path = path.string();
  resolve_site(options, result);
  // The site is checked by the /2 schema before anything is read.
  core::validate_or_throw(core::schema("import-meta-2.schema.json"),
                          nlohmann::json::parse(import_meta(result, 1.0).dump()),
                          "the site (--latitude, --height, --gravity)");

  std::unique_ptr<RecordingReader> reader = open_recording(path);
  result.format = reader->format();
  result.topic = choose_topic(*reader, options.topic, path, result);
  if (const auto t = reader->selected()) result.topic = *t;

  return detail::guarded("import " + path.string(), [&] {
    SQLite::Transaction tx(db.sql(), SQLite::TransactionBehavior::IMMEDIATE);
    SQLite::Statement run(db.sql(),
                          "INSERT INTO runs (procedure_name, procedure_text, procedure_sha256, "
                          "parameters, station_snapshot, status, created_utc) VALUES (?, '', "
                          "'', '{}', '{}', 'imported', ?)");
    run.bind(1, std::string(detail::kImportFormat2));
    run.bind(2, utc_now_iso8601());
    run.exec();
    result.run = db.sql().getLastInsertRowid();

    detail::StepRow step;
    step.label = "recording";
    step.commanded = {{"mode", "recording"}, {"orientation", "unknown"}};
    step.origin = fmt::format("{} {}", path.string(), result.topic.name);
    detail::StepStreamWriter writer(db.sql(), result.run, step, kImportDevice);
    StampCheck stamps(result);
    std::vector<ImuRecord> batch;
    std::vector<core::ImuSample> samples;
    std::uint32_t sequence = 0;
    double fraction = 0.0;
    // The reader is not touched here again before the prefetch has ended (its destructor
    // joins the thread; next() returning false means the thread is done with the reader).
    detail::BatchPrefetch<RecordingReader, ImuRecord> prefetch(*reader, options.batch);
    while (prefetch.next(batch, fraction)) {
      samples.resize(batch.size());
      for (std::size_t i = 0; i < batch.size(); ++i) {
        core::ImuSample& s = samples[i];
        s.receive_time_s = batch[i].t_s;
        s.device_time_s = batch[i].t_s;
        s.sequence = sequence++;
        for (int k = 0; k < 3; ++k) s.gyro_dps[k] = batch[i].gyro_rad_s[k] * kRecordingDegPerRad;
        s.accel_mps2 = batch[i].accel_mps2;
        s.temperature_c = std::numeric_limits<double>::quiet_NaN();
        stamps.add(s.receive_time_s);
      }
      writer.append(samples);
      result.samples += samples.size();
      if (options.progress) options.progress(fraction, result.samples);
    }
    if (result.samples == 0) {
      throw core::InputError(
          reader->position(),
          fmt::format("no messages on topic {}: nothing to import", result.topic.name));
    }
    stamps.finish();
    writer.finish();
    if (const auto t = reader->selected()) {
      result.topic.type = t->type;
      result.topic.encoding = t->encoding;
    }
    result.rate_hz = result.period_s > 0.0 ? 1.0 / result.period_s : 1.0;

    const std::string meta = import_meta(result, result.rate_hz).dump(2) + "\n";
    nlohmann::ordered_json parameters;
    parameters["source"] = std::filesystem::absolute(path).string();
    parameters["recording"] = {{"format", result.format},
                               {"topic", result.topic.name},
                               {"type", result.topic.type},
                               {"encoding", result.topic.encoding},
                               {"site", result.site_source}};
    SQLite::Statement update(db.sql(),
                             "UPDATE runs SET procedure_text = ?, procedure_sha256 = ?, "
                             "station_snapshot = ?, started_clock_s = ?, ended_clock_s = ?, "
                             "parameters = ? WHERE id = ?");
    update.bind(1, meta);
    update.bind(2, sha256_hex(meta));
    update.bind(3, nlohmann::json::parse(meta).dump());
    update.bind(4, std::min(result.first_s, result.last_s));
    update.bind(5, std::max(result.first_s, result.last_s));
    update.bind(6, parameters.dump());
    update.bind(7, result.run);
    update.exec();
    tx.commit();
    return result;
  });
}

}  // namespace calstand::store

// calstand import / export: moves runs in and out of a database as `calstand-import/1` folders
// (meta.json + samples.csv, ../shared/docs/error-model.md), e.g. data recorded by another
// station, or a run handed to another tool; and imports the recordings users have (ROS 1 and
// ROS 2 bags, MCAP, EuRoC/TUM-VI: store/import_recording.hpp).
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "open_database.hpp"
#include "store/database.hpp"
#include "store/import_export.hpp"
#include "store/import_recording.hpp"

namespace calstand::cli {
namespace {

struct ImportOptions {
  std::string dir;
  std::string db = "calstand.db";
  bool json = false;
  std::string topic;
  std::optional<double> latitude_deg;
  std::optional<double> height_m;
  std::optional<double> gravity_mps2;
};

/// A one-line progress display of a long import on a terminal (stderr), redrawn at most every
/// 200 ms; nothing when stderr is not a terminal or the output is JSON.
class ImportProgress {
 public:
  explicit ImportProgress(bool json) : enabled_(!json && ::isatty(STDERR_FILENO) == 1) {}
  void update(double fraction, std::uint64_t samples) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (drawn_ && now - last_ < std::chrono::milliseconds(200)) return;
    last_ = now;
    drawn_ = true;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth + 0.5);
    std::fprintf(stderr, "\rimport [%s%s] %3.0f%% %llu samples", std::string(filled, '#').c_str(),
                 std::string(kWidth - std::min(filled, kWidth), '.').c_str(), 100.0 * fraction,
                 static_cast<unsigned long long>(samples));
    std::fflush(stderr);
  }
  /// Draws the last state and ends the line, before the result is printed.
  void finish(std::uint64_t samples) {
    if (!drawn_) return;
    drawn_ = false;  // the next update draws at once
    update(1.0, samples);
    std::fputs("\n", stderr);
    drawn_ = false;
  }
  ~ImportProgress() {
    if (drawn_) std::fputs("\n", stderr);  // an import that failed midway
  }
  ImportProgress(const ImportProgress&) = delete;
  ImportProgress& operator=(const ImportProgress&) = delete;

 private:
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_{};
};

void print_recording_summary(const store::RecordingImportResult& r) {
  std::cerr << fmt::format("{}: {} {} ({}, {}): {} samples, {:.1f} s at {:.6g} Hz\n", r.path,
                           r.format, r.topic.name, r.topic.type, r.topic.encoding, r.samples,
                           r.last_s - r.first_s, r.rate_hz);
  std::cerr << fmt::format("site: latitude {} deg, height {} m, gravity {:.6f} m/s^2 ({})\n",
                           r.latitude_deg, r.height_m, r.gravity_mps2, r.site_source);
  if (r.gaps > 0) {
    std::cerr << fmt::format(
        "gaps: {} longer than 1.5 periods, {:.6g} s missing; the longest "
        "{:.6g} s before t = {:.9f} s\n",
        r.gaps, r.gap_time_s, r.largest_gap_s, r.largest_gap_at_s);
  } else {
    std::cerr << "gaps: none\n";
  }
  if (r.out_of_order > 0 || r.duplicates > 0) {
    std::cerr << fmt::format(
        "stamps: {} out of order, {} repeated (samples kept in recorded "
        "order)\n",
        r.out_of_order, r.duplicates);
  }
}

void run_recording_import(const ImportOptions& o) {
  store::RecordingImportOptions options;
  options.topic = o.topic;
  options.latitude_deg = o.latitude_deg;
  options.height_m = o.height_m;
  options.gravity_mps2 = o.gravity_mps2;
  ImportProgress progress(o.json);
  options.progress = [&](double f, std::uint64_t n) { progress.update(f, n); };
  store::Database db(o.db);
  const store::RecordingImportResult r = store::import_recording(db, o.dir, options);
  progress.finish(r.samples);
  if (o.json) {
    std::cout << r.to_json().dump() << "\n";
    return;
  }
  std::cout << r.run << "\n";
  print_recording_summary(r);
}

struct ExportOptions {
  std::string format = "calstand";
  std::string db = "calstand.db";
  std::int64_t run = 0;
  std::string out;
  std::string device;
};

void run_import(const ImportOptions& o) {
  const auto format = store::detect_recording_format(o.dir);
  // A folder of none of the kinds (no meta.json either) is refused by the recordings' message,
  // which lists every kind, rather than by a missing meta.json.
  if (!format || *format != "calstand-import") {
    run_recording_import(o);
    return;
  }
  for (const auto& [given, name] :
       {std::pair{!o.topic.empty(), "--topic"}, std::pair{o.latitude_deg.has_value(), "--latitude"},
        std::pair{o.height_m.has_value(), "--height"},
        std::pair{o.gravity_mps2.has_value(), "--gravity"}}) {
    if (given) {
      throw core::InputError(name,
                             "only for recordings (bags, MCAP, EuRoC); a calstand-import "
                             "folder's meta.json holds its site");
    }
  }
  store::ImportRunOptions options;
  ImportProgress progress(o.json);
  options.progress = [&](double f, std::uint64_t n) { progress.update(f, n); };
  store::Database db(o.db);
  const store::ImportResult r = store::import_run(db, o.dir, options);
  progress.finish(r.samples);
  if (o.json) {
    nlohmann::ordered_json j;
    j["run"] = r.run;
    j["steps"] = r.steps;
    j["samples"] = r.samples;
    std::cout << j.dump() << "\n";
  } else {
    std::cout << r.run << "\n";
  }
}

void run_export(const ExportOptions& o) {
  store::Database db = open_existing_database(o.db);
  if (o.format == "mcap") {
    store::export_run_mcap(db, o.run, o.out, {o.device});
    return;
  }
  store::export_run(db, o.run, o.out, {o.device});
}

}  // namespace

void register_import_export(CLI::App& app) {
  auto in = std::make_shared<ImportOptions>();
  CLI::App* imp =
      app.add_subcommand("import",
                         "Create a run from a calstand-import/1 or /2 folder (meta.json + "
                         "samples.csv), or from a recording: a ROS 1 bag, a ROS 2 bag (folder or "
                         ".db3), an MCAP file, a EuRoC/TUM-VI folder (found from the content); "
                         "prints the run id");
  imp->add_option("path", in->dir, "a calstand-import folder, or a recording")->required();
  imp->add_option("--db", in->db, "database file (created when absent)")->capture_default_str();
  imp->add_option("--topic", in->topic,
                  "recordings: the IMU topic (default: the only one); EuRoC: /imu0 for "
                  "mav0/imu0");
  imp->add_option("--latitude", in->latitude_deg,
                  "recordings: the site's latitude [deg] (default 45, said when used)");
  imp->add_option("--height", in->height_m, "recordings: the site's height [m] (default 0)");
  imp->add_option("--gravity", in->gravity_mps2,
                  "recordings: measured local gravity [m/s^2] (default: normal gravity)");
  imp->add_flag("--json", in->json,
                R"(print {"run": ID, "steps": N, "samples": M}; recordings: the import's summary)");
  imp->callback([in] { run_import(*in); });

  auto out = std::make_shared<ExportOptions>();
  CLI::App* exp = app.add_subcommand(
      "export", "Write a run as a calstand-import/1 folder (meta.json + samples.csv)");
  exp->add_option("--db", out->db, "database file")->capture_default_str();
  exp->add_option("--run", out->run, "run id (see calstand runs)")->required();
  exp->add_option("--out", out->out,
                  "output folder (created; its two files are overwritten), or the .mcap file")
      ->required();
  exp->add_option("--format", out->format,
                  "calstand (a calstand-import folder) or mcap (ROS 2 sensor_msgs/Imu on "
                  "/imu/data, zstd chunks)")
      ->check(CLI::IsMember({"calstand", "mcap"}))
      ->capture_default_str();
  exp->add_option("--device", out->device, "IMU to export when the run has several");
  exp->callback([out] { run_export(*out); });
}

}  // namespace calstand::cli

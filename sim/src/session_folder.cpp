#include "sim/session_folder.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

namespace calstand::sim {

namespace {

nlohmann::json folder_vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

void folder_write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
}

}  // namespace

nlohmann::json session_meta_json(const SimSession& s, const SessionFolderOptions& o) {
  nlohmann::json meta;
  meta["format"] = "calstand-import/2";
  meta["site"] = {{"latitude_deg", s.site.latitude_deg},
                  {"height_m", s.site.height_m},
                  {"gravity_mps2", s.gravity_mps2}};
  meta["sample_rate_hz"] = s.sample_rate_hz;
  nlohmann::json units = {{"gyro", o.counts ? "counts" : "deg/s"},
                          {"accel", o.counts ? "counts" : "m/s^2"},
                          {"time", "s"}};
  if (o.temperature) units["temperature"] = "degC";
  meta["units"] = units;
  if (o.counts) {
    meta["nominal"] = {
        {"gyro",
         {{"offset_counts",
           {kSessionGyroOffsetCounts, kSessionGyroOffsetCounts, kSessionGyroOffsetCounts}},
          {"counts_per_dps",
           {kSessionGyroCountsPerDps, kSessionGyroCountsPerDps, kSessionGyroCountsPerDps}}}},
        {"accel",
         {{"offset_counts",
           {kSessionAccelOffsetCounts, kSessionAccelOffsetCounts, kSessionAccelOffsetCounts}},
          {"counts_per_mps2",
           {kSessionAccelCountsPerMps2, kSessionAccelCountsPerMps2, kSessionAccelCountsPerMps2}}}}};
  }
  if (s.kind == "ferraris") {
    nlohmann::json sections = nlohmann::json::object();
    for (const auto& [step, label] : s.step_labels) {
      nlohmann::json sec;
      sec["label"] = label;
      bool found = false;
      for (const SessionHold& h : s.holds) {
        if (h.label == label) {
          sec["kind"] = "static";
          // The nominal axis of the label (x_p: +x up, x_a: -x up).
          sec["up"] = std::string(label.size() > 2 && label[2] == 'a' ? "-" : "+") + label[0];
          found = true;
        }
      }
      for (const SessionTurn& t : s.turns) {
        if (!found && t.label == label) {
          sec["kind"] = "turn";
          sec["axis"] = std::string("+") + label[0];
          // Right-handed about +axis (the axis is up during the turn).
          sec["angle_deg"] = t.angle_deg * (t.axis_A[label[0] - 'x'] >= 0.0 ? 1.0 : -1.0);
        }
      }
      sections[std::to_string(step)] = sec;
    }
    meta["sections"] = sections;
  }
  return meta;
}

nlohmann::json session_truth_json(const SimSession& s) {
  nlohmann::json j;
  j["format"] = "calstand-sim-session-truth/1";
  j["kind"] = s.kind;
  j["model"] = s.model_name;
  j["seed"] = s.seed;
  j["frame"] =
      "accelerometer triad A: body x along the accel x sensitive axis, body y in the plane of "
      "accel x and y, z completing; accel_misalignment .xy .xz .yz are zero by convention";
  j["C_AB"] = {folder_vec(s.truth.C_AB.row(0)), folder_vec(s.truth.C_AB.row(1)),
               folder_vec(s.truth.C_AB.row(2))};
  nlohmann::json params = nlohmann::json::object();
  for (const auto& [name, value] : s.truth.parameters()) params[name] = value;
  j["parameters"] = params;
  j["units"] = {{"accel_bias", "m/s^2"},
                {"accel_scale", "ppm"},
                {"accel_misalignment", "rad"},
                {"gyro_bias", "deg/s"},
                {"gyro_scale", "ppm"},
                {"gyro_misalignment", "rad"},
                {"gyro_g_sensitivity", "(deg/s)/g"}};
  static const char* channel[] = {"gyro_bias.x",  "gyro_bias.y",  "gyro_bias.z",
                                  "accel_bias.x", "accel_bias.y", "accel_bias.z"};
  nlohmann::json holds_mean = nlohmann::json::object();
  nlohmann::json rest_mean = nlohmann::json::object();
  for (std::size_t c = 0; c < 6; ++c) {
    holds_mean[channel[c]] = s.slow_noise_mean_holds[c];
    rest_mean[channel[c]] = s.slow_noise_mean_rest[c];
  }
  nlohmann::json session;
  session["slow_noise_mean_over_holds"] = holds_mean;
  session["comment"] =
      "slow noise (bias instability, Gauss-Markov, random walk) averaged over the static "
      "samples: part of the bias a calibration of this session sees";
  if (s.kind == "hand" && !s.holds.empty()) {
    session["initial_rest"] = {{"start_s", s.holds.front().start_s},
                               {"end_s", s.holds.front().end_s},
                               {"slow_noise_mean", rest_mean},
                               {"true_rate_A_dps", folder_vec(s.rest_true_rate_A_dps)}};
  }
  j["session"] = session;
  nlohmann::json holds = nlohmann::json::array();
  for (const SessionHold& h : s.holds) {
    nlohmann::json x = {{"start_s", h.start_s}, {"end_s", h.end_s}, {"up_A", folder_vec(h.up_A)}};
    if (!h.label.empty()) {
      x["label"] = h.label;
      x["placement_tilt_deg"] = h.placement_tilt_deg;
    }
    holds.push_back(x);
  }
  j["holds"] = holds;
  nlohmann::json turns = nlohmann::json::array();
  for (const SessionTurn& t : s.turns) {
    nlohmann::json x = {{"start_s", t.start_s},
                        {"end_s", t.end_s},
                        {"axis_A", folder_vec(t.axis_A)},
                        {"angle_deg", t.angle_deg},
                        {"peak_rate_dps", t.peak_rate_dps}};
    if (!t.label.empty()) x["label"] = t.label;
    turns.push_back(x);
  }
  j["turns"] = turns;
  return j;
}

void write_session_folder(const SimSession& s, const std::filesystem::path& dir,
                          const SessionFolderOptions& o) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create: " + ec.message());
  folder_write_text(dir / "meta.json", session_meta_json(s, o).dump(2) + "\n");
  folder_write_text(dir / "truth.json", session_truth_json(s).dump(2) + "\n");

  const std::filesystem::path csv = dir / "samples.csv";
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(csv.c_str(), "wb"), &std::fclose);
  if (!f) throw std::runtime_error(csv.string() + ": cannot write");
  const bool steps = !s.steps.empty();
  std::string header = "t,gx,gy,gz,ax,ay,az";
  if (o.temperature) header += ",temp_c";
  if (steps) header += ",step";
  std::fprintf(f.get(), "%s\n", header.c_str());
  fmt::memory_buffer line;
  for (std::size_t k = 0; k < s.samples.size(); ++k) {
    const core::ImuSample& x = s.samples[k];
    line.clear();
    fmt::format_to(std::back_inserter(line), "{:.6f}", x.receive_time_s);
    for (int i = 0; i < 3; ++i) {
      if (o.counts) {
        fmt::format_to(
            std::back_inserter(line), ",{:.0f}",
            std::round(kSessionGyroOffsetCounts + kSessionGyroCountsPerDps * x.gyro_dps[i]));
      } else {
        fmt::format_to(std::back_inserter(line), ",{:.9g}", x.gyro_dps[i]);
      }
    }
    for (int i = 0; i < 3; ++i) {
      if (o.counts) {
        fmt::format_to(
            std::back_inserter(line), ",{:.0f}",
            std::round(kSessionAccelOffsetCounts + kSessionAccelCountsPerMps2 * x.accel_mps2[i]));
      } else {
        fmt::format_to(std::back_inserter(line), ",{:.9g}", x.accel_mps2[i]);
      }
    }
    if (o.temperature) fmt::format_to(std::back_inserter(line), ",{:.3f}", x.temperature_c);
    if (steps) fmt::format_to(std::back_inserter(line), ",{}", s.steps[k]);
    line.push_back('\n');
    std::fwrite(line.data(), 1, line.size(), f.get());
  }
  if (std::ferror(f.get()) != 0) throw std::runtime_error(csv.string() + ": write failed");
}

}  // namespace calstand::sim

// EuRoC MAV / TUM-VI folders (ASL dataset format: Burri et al., "The EuRoC micro aerial vehicle
// datasets", IJRR 2016, and the TUM-VI benchmark's identical layout): mav0/imuN/data.csv with
// the header `#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y,w_RS_S_z,a_RS_S_x [m s^-2],a_RS_S_y,
// a_RS_S_z` (time stamps in integer nanoseconds, angular rate in rad/s, specific force in
// m/s^2), and mav0/imuN/sensor.yaml with the nominal `rate_hz`.

#include <fmt/format.h>

#include <algorithm>
#include <fstream>

#include "core/csv_reader.hpp"
#include "recording_detail.hpp"

namespace calstand::store::recordings {
namespace {

constexpr std::size_t kEurocColumns = 7;

// rate_hz from a sensor.yaml (a `rate_hz: 200` line), 0 when absent.
double sensor_rate_hz(const std::filesystem::path& yaml) {
  std::ifstream in(yaml);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.starts_with("rate_hz:")) continue;
    std::string_view v = std::string_view(line).substr(8);
    v = v.substr(0, v.find('#'));
    while (!v.empty() && (v.front() == ' ' || v.front() == '\t')) v.remove_prefix(1);
    while (!v.empty() && (v.back() == ' ' || v.back() == '\r' || v.back() == '\t')) {
      v.remove_suffix(1);
    }
    const auto rate = core::parse_csv_number(v);
    return rate ? *rate : 0.0;
  }
  return 0.0;
}

std::uint64_t count_lines(const std::filesystem::path& file) {
  std::FILE* f = std::fopen(file.string().c_str(), "rb");
  if (f == nullptr) return 0;
  std::vector<char> buf(std::size_t{1} << 20);
  std::uint64_t lines = 0;
  char last = '\n';
  std::size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), f)) > 0) {
    lines += static_cast<std::uint64_t>(std::count(buf.data(), buf.data() + n, '\n'));
    last = buf[n - 1];
  }
  std::fclose(f);
  return lines + (last == '\n' ? 0 : 1);
}

class EurocReader final : public RecordingReader {
 public:
  explicit EurocReader(const std::filesystem::path& path)
      : mav0_(path.filename() == "mav0" ? path : path / "mav0") {
    std::vector<std::filesystem::path> dirs;
    for (const auto& e : std::filesystem::directory_iterator(mav0_)) {
      if (e.path().filename().string().starts_with("imu") &&
          std::filesystem::is_regular_file(e.path() / "data.csv")) {
        dirs.push_back(e.path());
      }
    }
    std::sort(dirs.begin(), dirs.end());
    for (const auto& d : dirs) {
      TopicInfo t;
      t.name = "/" + d.filename().string();
      t.type = "EuRoC IMU (data.csv)";
      t.encoding = "csv";
      t.imu = true;
      const std::uint64_t lines = count_lines(d / "data.csv");
      t.count = lines > 0 ? lines - 1 : 0;
      t.rate_hz = sensor_rate_hz(d / "sensor.yaml");
      topics_.push_back(t);
    }
  }

  std::string format() const override { return "euroc"; }
  std::vector<TopicInfo> topics() override { return topics_; }

  void select(const std::string& topic) override {
    const auto it = std::find_if(topics_.begin(), topics_.end(),
                                 [&](const TopicInfo& t) { return t.name == topic; });
    if (it == topics_.end()) {
      std::string names;
      for (const auto& t : topics_) names += (names.empty() ? "" : ", ") + t.name;
      throw core::InputError(mav0_.string(),
                             fmt::format("no topic {} (a EuRoC folder's topics are its "
                                         "mav0/imuN folders: {})",
                                         topic, names));
    }
    selected_ = *it;
    expected_ = it->count;
    rows_ = 0;
    csv_ = std::make_unique<core::CsvReader>(mav0_ / topic.substr(1) / "data.csv");
    if (csv_->columns().size() != kEurocColumns || !csv_->columns()[0].starts_with("#timestamp")) {
      throw core::InputError(csv_->file() + ":1",
                             fmt::format("not a EuRoC IMU header (#timestamp [ns], w_RS_S_x/y/z "
                                         "[rad s^-1], a_RS_S_x/y/z [m s^-2]): '{}'",
                                         csv_->header()));
    }
  }

  bool read(std::vector<ImuRecord>& batch, std::size_t max) override {
    batch.clear();
    while (batch.size() < max && csv_->next()) {
      ImuRecord r;
      const std::int64_t ns = csv_->integer(0);
      if (ns < 0) throw core::InputError(csv_->where(), "column #timestamp: negative");
      r.t_s = stamp_seconds(ns / 1000000000, static_cast<std::uint32_t>(ns % 1000000000));
      for (int i = 0; i < 3; ++i) {
        r.gyro_rad_s[i] = csv_->number(1 + static_cast<std::size_t>(i));
        r.accel_mps2[i] = csv_->number(4 + static_cast<std::size_t>(i));
      }
      batch.push_back(r);
      ++rows_;
    }
    return !batch.empty();
  }

  std::optional<TopicInfo> selected() const override { return selected_; }
  std::string position() const override { return csv_ ? csv_->where() : mav0_.string(); }
  double progress() const override {
    return expected_ == 0
               ? 1.0
               : std::min(1.0, static_cast<double>(rows_) / static_cast<double>(expected_));
  }

 private:
  std::filesystem::path mav0_;
  std::vector<TopicInfo> topics_;
  std::optional<TopicInfo> selected_;
  std::unique_ptr<core::CsvReader> csv_;
  std::uint64_t expected_ = 0;
  std::uint64_t rows_ = 0;
};

}  // namespace

std::unique_ptr<RecordingReader> open_euroc(const std::filesystem::path& folder) {
  return std::make_unique<EurocReader>(folder);
}

}  // namespace calstand::store::recordings

// ROS 2 bags (rosbag2): a folder with metadata.yaml (rosbag2_bagfile_information: the storage
// plugin, storage_identifier "sqlite3" or "mcap", and relative_file_paths, the storage files
// in order) and its storage files. The sqlite3 storage (rosbag2_storage_default_plugins,
// sqlite_storage.cpp) has a table topics (id, name, type, serialization_format, ...) and a
// table messages (id, topic_id, timestamp [ns, receive time], data: the serialized message,
// CDR). The mcap storage writes standard MCAP files (mcap_reader.cpp).

#include <SQLiteCpp/Database.h>
#include <SQLiteCpp/Statement.h>
#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <limits>
#include <map>
#include <set>

#include "recording_detail.hpp"

namespace calstand::store::recordings {
namespace {

class Db3Source final : public MessageSource {
  // SQLite errors while reading (a corrupt or truncated file) as InputErrors at the row.
  template <class F>
  auto guard(F&& fn) -> decltype(fn()) {
    try {
      return fn();
    } catch (const SQLite::Exception& e) {
      throw core::InputError(position(), fmt::format("reading the sqlite3 file: {}", e.what()));
    }
  }

 public:
  explicit Db3Source(const std::filesystem::path& path) : name_(path.string()) {
    try {
      db_ = std::make_unique<SQLite::Database>(name_, SQLite::OPEN_READONLY);
      SQLite::Statement topics(*db_,
                               "SELECT id, name, type, serialization_format FROM topics "
                               "ORDER BY id");
      while (topics.executeStep()) {
        TopicInfo t;
        t.name = topics.getColumn(1).getString();
        t.type = topics.getColumn(2).getString();
        t.encoding = topics.getColumn(3).getString();
        t.imu = is_imu_type(t.type, t.encoding);
        index_[topics.getColumn(0).getInt64()] = static_cast<int>(channels_.size());
        channels_.push_back(t);
      }
      SQLite::Statement counts(*db_,
                               "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) "
                               "FROM messages GROUP BY topic_id");
      while (counts.executeStep()) {
        const auto it = index_.find(counts.getColumn(0).getInt64());
        if (it == index_.end()) continue;
        TopicInfo& t = channels_[static_cast<std::size_t>(it->second)];
        t.count = static_cast<std::uint64_t>(counts.getColumn(1).getInt64());
        const double span =
            static_cast<double>(counts.getColumn(3).getInt64() - counts.getColumn(2).getInt64());
        t.rate_hz =
            t.count > 1 && span > 0 ? static_cast<double>(t.count - 1) / (span * 1e-9) : 0.0;
        total_ += t.count;
      }
    } catch (const SQLite::Exception& e) {
      throw core::InputError(name_, fmt::format("not a readable rosbag2 sqlite3 file (tables "
                                                "topics and messages): {}",
                                                e.what()));
    }
  }

  std::string format() const override { return "ros2-bag"; }
  std::string name() const override { return name_; }
  const std::vector<TopicInfo>& channels() const override { return channels_; }
  bool indexed() const override { return true; }

  void rewind(int only) override {
    rows_ = 0;
    row_id_ = 0;
    done_ = false;
    guard([&] {
      if (only >= 0) {
        std::int64_t id = 0;
        for (const auto& [topic_id, i] : index_) {
          if (i == only) id = topic_id;
        }
        query_ = std::make_unique<SQLite::Statement>(
            *db_,
            "SELECT id, topic_id, timestamp, data FROM messages WHERE topic_id = ? "
            "ORDER BY id");
        query_->bind(1, id);
      } else {
        query_ = std::make_unique<SQLite::Statement>(
            *db_, "SELECT id, topic_id, timestamp, data FROM messages ORDER BY id");
      }
    });
  }

  bool next(RawMessage& m) override {
    return guard([&] {
      if (done_ || !query_->executeStep()) {
        done_ = true;  // SQLite refuses a step after the last
        return false;
      }
      ++rows_;
      row_id_ = query_->getColumn(0).getInt64();
      const auto it = index_.find(query_->getColumn(1).getInt64());
      if (it == index_.end()) {
        throw core::InputError(position(), fmt::format("message of topic_id {}, which the topics "
                                                       "table does not have",
                                                       query_->getColumn(1).getInt64()));
      }
      m.channel = static_cast<std::uint32_t>(it->second);
      m.log_time_ns = static_cast<std::uint64_t>(query_->getColumn(2).getInt64());
      const SQLite::Column data = query_->getColumn(3);
      m.data = {static_cast<const std::uint8_t*>(data.getBlob()),
                static_cast<std::size_t>(data.getBytes())};
      return true;
    });
  }

  std::string position() const override {
    return fmt::format("{}: messages row id {}", name_, row_id_);
  }
  double progress() const override {
    return total_ == 0 ? 1.0 : static_cast<double>(rows_) / static_cast<double>(total_);
  }

 private:
  std::string name_;
  std::unique_ptr<SQLite::Database> db_;
  std::unique_ptr<SQLite::Statement> query_;
  std::vector<TopicInfo> channels_;
  std::map<std::int64_t, int> index_;  // topics.id -> channel
  std::uint64_t total_ = 0;
  std::uint64_t rows_ = 0;
  std::int64_t row_id_ = 0;
  bool done_ = false;
};

/// The storage files of a bag folder, in order, from metadata.yaml (relative_file_paths), or
/// every .db3 and .mcap file of the folder by name when it lists none. A small reader of the
/// two keys rather than a YAML library: rosbag2 writes them as `key: value` and a block list
/// of `- name` items.
std::vector<std::filesystem::path> storage_files(const std::filesystem::path& folder) {
  std::ifstream in(folder / "metadata.yaml");
  std::vector<std::filesystem::path> files;
  std::string line;
  bool in_list = false;
  while (std::getline(in, line)) {
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos) continue;
    std::string_view s(line);
    s.remove_prefix(first);
    if (s.starts_with("relative_file_paths:")) {
      in_list = true;
      continue;
    }
    if (in_list && s.starts_with("- ")) {
      std::string name(s.substr(2));
      while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.pop_back();
      if (name.size() >= 2 && (name.front() == '"' || name.front() == '\'')) {
        name = name.substr(1, name.size() - 2);
      }
      files.push_back(folder / name);
      continue;
    }
    in_list = false;
  }
  if (files.empty()) {
    for (const auto& e : std::filesystem::directory_iterator(folder)) {
      const auto ext = e.path().extension();
      if (ext == ".db3" || ext == ".mcap") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
  }
  return files;
}

/// A bag of several storage files read as one: channels merged by topic name.
class ChainSource final : public MessageSource {
 public:
  explicit ChainSource(std::vector<std::filesystem::path> files) : files_(std::move(files)) {
    for (std::size_t i = 0; i < files_.size(); ++i) {
      open(i);
      if (!current_->indexed()) indexed_ = false;
      merge();
    }
    rewind(-1);
  }

  std::string format() const override { return "ros2-bag"; }
  std::string name() const override { return files_.front().parent_path().string(); }
  const std::vector<TopicInfo>& channels() const override { return channels_; }
  bool indexed() const override { return indexed_; }

  void rewind(int only) override {
    only_ = only;
    open(0);
    rewind_current();
  }

  bool next(RawMessage& m) override {
    for (;;) {
      if (!skip_ && current_->next(m)) {
        merge();
        m.channel = static_cast<std::uint32_t>(map_[m.channel]);
        if (only_ >= 0 && static_cast<int>(m.channel) != only_) continue;
        return true;
      }
      if (file_ + 1 >= files_.size()) return false;
      open(file_ + 1);
      rewind_current();
    }
  }

  std::string position() const override { return current_->position(); }
  double progress() const override {
    return (static_cast<double>(file_) + current_->progress()) / static_cast<double>(files_.size());
  }

 private:
  void open(std::size_t i) {
    if (current_ && file_ == i) return;
    file_ = i;
    map_.clear();
    const auto& f = files_[i];
    if (!std::filesystem::is_regular_file(f)) {
      throw core::InputError(f.string(), "a storage file metadata.yaml lists is missing");
    }
    const auto format = detect_recording_format(f);
    if (format == "mcap") {
      current_ = open_mcap(f);
    } else if (format == "ros2-bag") {
      current_ = std::make_unique<Db3Source>(f);
    } else {
      throw core::InputError(f.string(), "neither a sqlite3 nor an MCAP file");
    }
  }

  void rewind_current() {
    int only = -1;
    skip_ = false;
    if (only_ >= 0) {
      merge();
      for (std::size_t k = 0; k < map_.size(); ++k) {
        if (map_[k] == only_) only = static_cast<int>(k);
      }
      // Absent from a file with an index: nothing to read there. (A file without one may
      // define the channel as it goes, and is read whole.)
      skip_ = only < 0 && current_->indexed();
    }
    if (!skip_) current_->rewind(only);
  }

  // Maps the current file's channels (those known so far) to merged ones.
  void merge() {
    const auto& ch = current_->channels();
    for (std::size_t k = map_.size(); k < ch.size(); ++k) {
      int found = -1;
      for (std::size_t j = 0; j < channels_.size(); ++j) {
        if (channels_[j].name == ch[k].name) found = static_cast<int>(j);
      }
      if (found < 0) {
        found = static_cast<int>(channels_.size());
        channels_.push_back(ch[k]);
        channels_.back().count = 0;
      }
      if (!merged_counts_.contains({file_, k})) {
        merged_counts_.insert({file_, k});
        channels_[static_cast<std::size_t>(found)].count += ch[k].count;
        channels_[static_cast<std::size_t>(found)].rate_hz =
            std::max(channels_[static_cast<std::size_t>(found)].rate_hz, ch[k].rate_hz);
      }
      map_.push_back(found);
    }
  }

  std::vector<std::filesystem::path> files_;
  std::unique_ptr<MessageSource> current_;
  std::size_t file_ = 0;
  std::vector<int> map_;  // current file's channel -> merged channel
  std::set<std::pair<std::size_t, std::size_t>> merged_counts_;
  std::vector<TopicInfo> channels_;
  bool indexed_ = true;
  int only_ = -1;
  bool skip_ = false;
};

}  // namespace

std::unique_ptr<MessageSource> open_ros2_bag(const std::filesystem::path& path) {
  if (std::filesystem::is_directory(path)) {
    auto files = storage_files(path);
    if (files.empty()) {
      throw core::InputError((path / "metadata.yaml").string(),
                             "no storage files (relative_file_paths lists none, and the folder "
                             "has no .db3 or .mcap file)");
    }
    if (files.size() == 1 && detect_recording_format(files[0]) == "ros2-bag") {
      return std::make_unique<Db3Source>(files[0]);
    }
    return std::make_unique<ChainSource>(std::move(files));
  }
  return std::make_unique<Db3Source>(path);
}

}  // namespace calstand::store::recordings

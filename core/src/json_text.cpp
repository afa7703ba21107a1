#include <cerrno>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <system_error>

#include "json_schema_internal.hpp"

namespace calstand::core {

using nlohmann::json;

namespace schema_detail {
namespace {

/// 1-based line and character column of the 1-based byte position nlohmann reports.
std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t byte) {
  const std::size_t pos = std::min(byte == 0 ? 0 : byte - 1, text.size());
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < pos; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else if ((static_cast<unsigned char>(text[i]) & 0xC0u) != 0x80u) {
      ++column;
    }
  }
  return {line, column};
}

/// nlohmann's reason without its exception id and its own (byte-based) location.
std::string parse_reason(const json::parse_error& e) {
  const std::string what = e.what();
  const std::size_t at = what.find("column ");
  const std::size_t colon = at == std::string::npos ? at : what.find(": ", at);
  if (colon != std::string::npos) return what.substr(colon + 2);
  const std::size_t bracket = what.find("] ");
  return bracket == std::string::npos ? what : what.substr(bracket + 2);
}

/// Finds the first key repeated within one object, with the JSON path of that object.
class DuplicateKeyFinder : public nlohmann::json_sax<json> {
 public:
  bool null() override { return element(); }
  bool boolean(bool) override { return element(); }
  bool number_integer(number_integer_t) override { return element(); }
  bool number_unsigned(number_unsigned_t) override { return element(); }
  bool number_float(number_float_t, const string_t&) override { return element(); }
  bool string(string_t&) override { return element(); }
  bool binary(binary_t&) override { return element(); }
  bool start_object(std::size_t) override {
    element();
    frames_.emplace_back(true);
    return true;
  }
  bool key(string_t& k) override {
    Frame& f = frames_.back();
    if (!f.keys.insert(k).second) {
      duplicate_ = k;
      duplicate_path_ = path_to(frames_.size() - 1);
      return false;  // stops the parse
    }
    f.key = k;
    return true;
  }
  bool end_object() override {
    frames_.pop_back();
    return true;
  }
  bool start_array(std::size_t) override {
    element();
    frames_.emplace_back(false);
    return true;
  }
  bool end_array() override {
    frames_.pop_back();
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const json::exception&) override {
    return false;  // the DOM parse already reported syntax errors
  }

  const std::optional<std::string>& duplicate() const { return duplicate_; }
  const std::string& duplicate_path() const { return duplicate_path_; }

 private:
  struct Frame {
    explicit Frame(bool object) : is_object(object) {}
    bool is_object;
    std::string key;        // current member, objects
    std::size_t index = 0;  // current element, arrays
    std::size_t count = 0;  // elements seen, arrays
    std::set<std::string> keys;
  };

  bool element() {
    if (!frames_.empty() && !frames_.back().is_object)
      frames_.back().index = frames_.back().count++;
    return true;
  }

  std::string path_to(std::size_t depth) const {
    std::string path;
    for (std::size_t i = 0; i < depth; ++i) {
      path = frames_[i].is_object ? member_path(path, frames_[i].key)
                                  : index_path(path, frames_[i].index);
    }
    return path;
  }

  std::vector<Frame> frames_;
  std::optional<std::string> duplicate_;
  std::string duplicate_path_;
};

}  // namespace
}  // namespace schema_detail

json parse_json_text(std::string_view text, const std::string& file_name) {
  json doc;
  try {
    doc = json::parse(text.begin(), text.end());
  } catch (const json::parse_error& e) {
    const auto [line, column] = schema_detail::line_column(text, e.byte);
    throw InputError(file_name + ":" + std::to_string(line) + ":" + std::to_string(column),
                     "invalid JSON: " + schema_detail::parse_reason(e));
  }
  schema_detail::DuplicateKeyFinder finder;
  json::sax_parse(text.begin(), text.end(), &finder);
  if (finder.duplicate()) {
    const std::string& path = finder.duplicate_path();
    throw InputError(file_name, (path.empty() ? std::string() : path + ": ") + "key " +
                                    schema_detail::quote(*finder.duplicate()) +
                                    " appears more than once (only one value can be used)");
  }
  return doc;
}

json read_json_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(path, "is a directory, not a JSON file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int err = errno;
    throw InputError(path, "cannot open: " + std::generic_category().message(err));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, "cannot read the file");
  return parse_json_text(text.str(), path);
}
}  // namespace calstand::core

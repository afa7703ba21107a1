// The schema validator against the official JSON-Schema-Test-Suite (Debian package
// json-schema-test-suite), every case of draft-07, the newest draft the package holds, except
// those listed with a reason in json_schema_suite_skips.txt. Skipped, saying why, when the
// package is not installed; failed instead when CALSTAND_REQUIRE_SCHEMA_SUITE is set (the test
// command installs the package, so its absence there is an error).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/json_schema.hpp"

namespace calstand::core {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path suite_dir() {
  if (const char* dir = std::getenv("CALSTAND_SCHEMA_SUITE_DIR")) return dir;
  return "/usr/share/json-schema-test-suite/tests/draft7";
}

/// One line of the skip list: a file, a group of it or one case of a group, and why.
struct Skip {
  std::string file;   // relative to the draft directory, e.g. "optional/bignum.json"; "DIR/": all
  std::string group;  // empty: the whole file
  std::string test;   // empty: the whole group
  std::string reason;
  int line = 0;
  int used = 0;  // cases it skipped; an entry that skips nothing is stale
};

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

/// `FILE [| GROUP [| TEST]] -- REASON` per line; `#` starts a comment line.
std::vector<Skip> read_skips(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  std::vector<Skip> skips;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    if (trim(text).empty() || trim(text)[0] == '#') continue;
    const auto dashes = text.find(" -- ");
    if (dashes == std::string::npos || trim(text.substr(dashes + 4)).empty()) {
      throw std::runtime_error(path.string() + ":" + std::to_string(line) +
                               ": every skip needs a reason after \" -- \"");
    }
    Skip skip;
    skip.reason = trim(text.substr(dashes + 4));
    skip.line = line;
    std::vector<std::string> fields;
    std::string rest = text.substr(0, dashes);
    for (std::size_t bar; (bar = rest.find(" | ")) != std::string::npos; rest.erase(0, bar + 3)) {
      fields.push_back(trim(rest.substr(0, bar)));
    }
    fields.push_back(trim(rest));
    if (fields.size() > 3) {
      throw std::runtime_error(path.string() + ":" + std::to_string(line) +
                               ": at most FILE | GROUP | TEST before the reason");
    }
    skip.file = fields[0];
    if (fields.size() > 1) skip.group = fields[1];
    if (fields.size() > 2) skip.test = fields[2];
    skips.push_back(std::move(skip));
  }
  return skips;
}

Skip* find_skip(std::vector<Skip>& skips, const std::string& file, const std::string& group,
                const std::string& test) {
  for (auto& s : skips) {
    // "DIR/" names every file under DIR.
    const bool in_dir = s.file.back() == '/' && file.rfind(s.file, 0) == 0;
    if (s.file != file && !in_dir) continue;
    if (!s.group.empty() && s.group != group) continue;
    if (!s.test.empty() && s.test != test) continue;
    return &s;
  }
  return nullptr;
}

TEST(JsonSchemaSuite, Draft07CasesOfTheSupportedKeywordsPass) {
  const fs::path dir = suite_dir();
  if (!fs::is_directory(dir)) {
    const std::string missing =
        dir.string() + " not found: install the Debian package json-schema-test-suite";
    if (std::getenv("CALSTAND_REQUIRE_SCHEMA_SUITE")) {
      FAIL() << missing << " (CALSTAND_REQUIRE_SCHEMA_SUITE is set: the test command installs "
             << "the package, so its absence is an error)";
    }
    GTEST_SKIP() << missing;
  }
  std::vector<Skip> skips =
      read_skips(fs::path(CALSTAND_SOURCE_DIR) / "tests/unit/core/json_schema_suite_skips.txt");

  std::vector<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file() && entry.path().extension() == ".json") {
      files.push_back(entry.path().lexically_relative(dir).generic_string());
    }
  }
  std::sort(files.begin(), files.end());
  ASSERT_FALSE(files.empty()) << dir << " holds no test files";

  int passed = 0, skipped = 0, failed = 0;
  for (const auto& file : files) {
    const json groups = read_json_file((dir / file).string());
    for (const auto& group : groups) {
      const std::string group_name = group.at("description").get<std::string>();
      std::optional<JsonSchema> schema;
      std::string load_error;
      try {
        schema = JsonSchema::parse(group.at("schema"), file);
      } catch (const InputError& e) {
        load_error = e.what();
      }
      for (const auto& test : group.at("tests")) {
        const std::string test_name = test.at("description").get<std::string>();
        if (Skip* skip = find_skip(skips, file, group_name, test_name)) {
          ++skip->used;
          ++skipped;
          continue;
        }
        const std::string where = file + " | " + group_name + " | " + test_name;
        if (!schema) {
          ++failed;
          ADD_FAILURE() << where << ": the schema does not load: " << load_error;
          continue;
        }
        const auto violations = schema->validate(test.at("data"));
        const bool valid = violations.empty();
        if (valid == test.at("valid").get<bool>()) {
          ++passed;
          continue;
        }
        ++failed;
        ADD_FAILURE() << where << ": expected " << (valid ? "invalid" : "valid") << ", got "
                      << (valid ? "valid"
                                : "invalid: " + violations.front().path + ": " +
                                      violations.front().message);
      }
    }
  }
  for (const auto& s : skips) {
    EXPECT_GT(s.used, 0) << "json_schema_suite_skips.txt:" << s.line << " (" << s.file
                         << ") skips no case of the suite: remove it";
  }
  std::cout << "JSON-Schema-Test-Suite draft-07 (" << dir.string() << "): " << passed
            << " cases passed, " << failed << " failed, " << skipped << " skipped as listed in "
            << "json_schema_suite_skips.txt\n";
  EXPECT_GT(passed, 0);
}

}  // namespace
}  // namespace calstand::core

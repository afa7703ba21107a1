// The tokens file as `calstand token` edits it (wire/tokens_store.hpp): a token added is read
// back hashed, the file never holds its secret, names are unique, plain-text entries of older
// files still read.
#include "wire/tokens_store.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "wire/token_hash.hpp"

namespace {

using calstand::wire::add_hashed_token;
using calstand::wire::read_tokens_file;
using calstand::wire::remove_token;

std::string fresh_tokens_path(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("calstand-tokens-store-" + std::to_string(::getpid()) + "-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return (dir / "tokens.json").string();
}

std::string text_of(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(TokensStore, AnAddedTokenIsStoredHashedAndTheFileNeverHoldsItsSecret) {
  const std::string path = fresh_tokens_path("add");
  const std::string op = add_hashed_token(path, "lab-op", "operator");
  const std::string viewer = add_hashed_token(path, "display", "read");
  const std::string text = text_of(path);
  for (const std::string& secret : {op, viewer}) {
    EXPECT_EQ(text.find(secret), std::string::npos);
    EXPECT_EQ(text.find(secret.substr(17)), std::string::npos) << "the random part is in the file";
  }
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);

  const auto entries = read_tokens_file(path);
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[0].name, "lab-op");
  EXPECT_EQ(entries[0].role, "operator");
  EXPECT_TRUE(entries[0].hashed());
  EXPECT_TRUE(entries[0].plain_secret.empty());
  EXPECT_EQ(entries[0].id, calstand::wire::token_id_of(op));
  EXPECT_TRUE(calstand::wire::token_secret_matches(op, entries[0].hash, "t"));
  EXPECT_FALSE(calstand::wire::token_secret_matches(viewer, entries[0].hash, "t"));
  EXPECT_EQ(entries[1].role, "read");
}

TEST(TokensStore, NamesAreUniqueAndTheLastTokenStays) {
  const std::string path = fresh_tokens_path("names");
  add_hashed_token(path, "lab-op", "operator");
  EXPECT_THROW(add_hashed_token(path, "lab-op", "read"), calstand::core::InputError);
  EXPECT_THROW(add_hashed_token(path, "bad name", "read"), calstand::core::InputError);
  EXPECT_THROW(add_hashed_token(path, "x", "admin"), calstand::core::InputError);
  add_hashed_token(path, "second", "read");
  EXPECT_THROW(remove_token(path, "nobody"), calstand::core::InputError);
  remove_token(path, "second");
  ASSERT_EQ(read_tokens_file(path).size(), 1u);
  try {
    remove_token(path, "lab-op");
    ADD_FAILURE() << "the last token was removed";
  } catch (const calstand::core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("last token"), std::string::npos) << e.what();
  }
  EXPECT_EQ(read_tokens_file(path).size(), 1u);
}

TEST(TokensStore, APlainTextFileStillReadsAndMixesWithHashedEntries) {
  const std::string path = fresh_tokens_path("plain");
  std::ofstream(path) << R"({"format": "calstand-tokens/1", "tokens": [
      {"name": "old-op", "role": "operator", "token": "operator-0123456789abcdef"}]})";
  add_hashed_token(path, "new-op", "operator");
  const auto entries = read_tokens_file(path);
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_FALSE(entries[0].hashed());
  EXPECT_EQ(entries[0].plain_secret, "operator-0123456789abcdef");
  EXPECT_TRUE(entries[1].hashed());
  // An entry with both a secret and a hash is neither form: refused by the schema.
  std::ofstream(path) << R"({"format": "calstand-tokens/1", "tokens": [
      {"name": "odd", "role": "operator", "token": "operator-0123456789abcdef",
       "id": "0011223344556677", "hash": "$scrypt$ln=15,r=8,p=1$00112233$0011223344556677"}]})";
  EXPECT_THROW(read_tokens_file(path), calstand::core::InputError);
}

}  // namespace

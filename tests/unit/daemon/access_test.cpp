#include "daemon/api/access.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "daemon/api/api_server.hpp"
#include "daemon/api/tokens_file.hpp"
#include "wire/token_hash.hpp"
#include "wire/tokens_store.hpp"

namespace {

using namespace calstand::daemon::api;

TEST(Access, ConstantTimeEqualComparesWholeStrings) {
  EXPECT_TRUE(constant_time_equal("secret-token", "secret-token"));
  EXPECT_FALSE(constant_time_equal("secret-token", "secret-tokeN"));
  EXPECT_FALSE(constant_time_equal("secret", "secret-token"));  // a prefix is not enough
  EXPECT_FALSE(constant_time_equal("secret-token", ""));
  EXPECT_TRUE(constant_time_equal("", ""));
}

TEST(Access, BearerTokenNeedsTheSchemeAndTheExactToken) {
  EXPECT_TRUE(bearer_token_accepted("Bearer abc123", "abc123"));
  EXPECT_FALSE(bearer_token_accepted("abc123", "abc123"));
  EXPECT_FALSE(bearer_token_accepted("Basic abc123", "abc123"));
  EXPECT_FALSE(bearer_token_accepted("Bearer abc12", "abc123"));
  EXPECT_FALSE(bearer_token_accepted("", "abc123"));
  EXPECT_TRUE(bearer_token_accepted("", ""));  // no token configured
}

TEST(Access, OnlyLoopbackAddressesAreLoopback) {
  EXPECT_TRUE(is_loopback_address("127.0.0.1"));
  EXPECT_TRUE(is_loopback_address("127.1.2.3"));
  EXPECT_TRUE(is_loopback_address("::1"));
  EXPECT_TRUE(is_loopback_address("localhost"));
  EXPECT_FALSE(is_loopback_address("0.0.0.0"));
  EXPECT_FALSE(is_loopback_address("::"));
  EXPECT_FALSE(is_loopback_address("192.168.1.10"));
  EXPECT_FALSE(is_loopback_address("1270.0.0.1"));
}

TEST(Access, OperatorNamesAreSanitisedAndCarryTheAddress) {
  EXPECT_EQ(operator_name("alice", "10.0.0.2"), "alice@10.0.0.2");
  EXPECT_EQ(operator_name("", "127.0.0.1"), "api@127.0.0.1");
  EXPECT_EQ(operator_name("a b\n", "127.0.0.1"), "a?b?@127.0.0.1");
  EXPECT_EQ(operator_name(std::string(100, 'x'), "h"), std::string(64, 'x') + "@h");
}

TEST(Access, ApiOptionsRefuseAnOpenPortWithoutAToken) {
  ApiOptions o;
  o.host = "0.0.0.0";
  EXPECT_THROW(o.validate(), calstand::core::InputError);
  o.token = "0123456789abcdef";
  EXPECT_THROW(o.validate(), calstand::core::InputError);  // a token, but no TLS
  o.allow_plaintext = true;
  EXPECT_NO_THROW(o.validate());
  o.port = 70000;
  EXPECT_THROW(o.validate(), calstand::core::InputError);
}

TEST(Access, OperatorNamesCarryTheTokensName) {
  EXPECT_EQ(operator_name("alice", "10.0.0.2", "lab-op"), "alice@10.0.0.2 (token lab-op)");
  EXPECT_EQ(operator_name("", "10.0.0.2", ""), "api@10.0.0.2");
}

AccessPolicy two_roles(bool reads_need_token) {
  AccessPolicy p;
  p.tokens = {{"viewer", Role::kRead, "viewer-secret-0123"},
              {"lab-op", Role::kOperator, "op-secret-01234567"}};
  p.reads_need_token = reads_need_token;
  return p;
}

TEST(Access, WhatEachRequestNeeds) {
  const AccessPolicy p = two_roles(true);
  EXPECT_EQ(p.need_of("GET", "/"), Need::kNothing);
  EXPECT_EQ(p.need_of("GET", "/console/app.js"), Need::kNothing);
  EXPECT_EQ(p.need_of("GET", "/consolex"), Need::kRead);
  EXPECT_EQ(p.need_of("GET", "/events"), Need::kRead);
  EXPECT_EQ(p.need_of("HEAD", "/runs"), Need::kRead);
  EXPECT_EQ(p.need_of("POST", "/plan"), Need::kOperator);
  EXPECT_EQ(p.need_of("POST", "/console/app.js"), Need::kOperator);
  EXPECT_EQ(p.need_of("DELETE", "/runs/1"), Need::kOperator);
}

TEST(Access, RolesDecideBetween401And403) {
  const AccessPolicy beyond = two_roles(true);
  EXPECT_EQ(check_access(beyond, "GET", "/station", "").status, 401);
  EXPECT_EQ(check_access(beyond, "GET", "/station", "wrong-secret-012345").status, 401);
  EXPECT_EQ(check_access(beyond, "GET", "/station", "viewer-secret-0123").status, 0);
  EXPECT_EQ(check_access(beyond, "GET", "/", "").status, 0);
  EXPECT_EQ(check_access(beyond, "POST", "/runs", "").status, 401);
  const AccessDecision read_only = check_access(beyond, "POST", "/runs", "viewer-secret-0123");
  EXPECT_EQ(read_only.status, 403);
  EXPECT_NE(read_only.why.find("'viewer' may only read"), std::string::npos) << read_only.why;
  const AccessDecision op = check_access(beyond, "POST", "/runs", "op-secret-01234567");
  EXPECT_EQ(op.status, 0);
  ASSERT_NE(op.caller, nullptr);
  EXPECT_EQ(op.caller->name, "lab-op");

  const AccessPolicy loopback = two_roles(false);
  EXPECT_EQ(check_access(loopback, "GET", "/station", "").status, 0);
  EXPECT_EQ(check_access(loopback, "POST", "/runs", "").status, 401);
  const AccessPolicy open;  // loopback without tokens: as before tokens existed
  EXPECT_EQ(check_access(open, "POST", "/runs", "").status, 0);
  EXPECT_EQ(check_access(open, "POST", "/runs", "anything").caller, nullptr);
}

// A hashed token (calstand token add): the daemon holds its id and hash only, accepts the
// right secret (again from its memory of it), refuses a wrong one, one with another token's id,
// and one without an id; a plain token beside it still works.
TEST(Access, AHashedTokenAcceptsItsSecretOnly) {
  const auto op = calstand::wire::new_token_secret();
  const auto viewer = calstand::wire::new_token_secret();
  AccessPolicy p;
  p.tokens = {
      {"lab-op", Role::kOperator, "", op.id, calstand::wire::hash_token_secret(op.secret)},
      {"viewer", Role::kRead, "", viewer.id, calstand::wire::hash_token_secret(viewer.secret)},
      {"old-op", Role::kOperator, "op-secret-01234567", "", ""}};
  p.reads_need_token = true;
  for (int twice = 0; twice < 2; ++twice) {
    const AccessDecision ok = check_access(p, "POST", "/runs", op.secret);
    EXPECT_EQ(ok.status, 0);
    ASSERT_NE(ok.caller, nullptr);
    EXPECT_EQ(ok.caller->name, "lab-op");
  }
  std::string wrong = op.secret;
  wrong.back() = wrong.back() == 'a' ? 'b' : 'a';
  EXPECT_EQ(check_access(p, "POST", "/runs", wrong).status, 401);
  // The viewer's id with the operator's secret part: checked against the viewer's hash, refused.
  EXPECT_EQ(check_access(p, "GET", "/station", viewer.id + op.secret.substr(16)).status, 401);
  EXPECT_EQ(check_access(p, "GET", "/station", op.secret.substr(17)).status, 401);
  EXPECT_EQ(check_access(p, "POST", "/runs", viewer.secret).status, 403);
  EXPECT_EQ(check_access(p, "POST", "/runs", "op-secret-01234567").caller->name, "old-op");
  // The hash itself is no token.
  EXPECT_EQ(check_access(p, "GET", "/station", p.tokens[0].hash).status, 401);
}

TEST(TokensFile, ReadsHashedTokensWithoutTheirSecrets) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("calstand-access-hashed-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "tokens.json").string();
  std::filesystem::remove(path);
  const std::string secret = calstand::wire::add_hashed_token(path, "lab-op", "operator");
  const auto tokens = load_tokens_file(path);
  ASSERT_EQ(tokens.size(), 1u);
  EXPECT_TRUE(tokens[0].hashed());
  EXPECT_TRUE(tokens[0].secret.empty());
  AccessPolicy p;
  p.tokens = tokens;
  EXPECT_EQ(check_access(p, "POST", "/runs", secret).status, 0);
  EXPECT_EQ(check_access(p, "POST", "/runs", secret + "x").status, 401);
  std::filesystem::remove_all(dir);
}

TEST(Access, BearerOfTakesOnlyTheBearerScheme) {
  EXPECT_EQ(bearer_of("Bearer abc"), "abc");
  EXPECT_EQ(bearer_of("Basic abc"), "");
  EXPECT_EQ(bearer_of(""), "");
}

std::string tokens_file_with(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("calstand-tokens-" + std::to_string(::getpid()) + "-" + name + ".json");
  std::ofstream(path) << text;
  return path.string();
}

TEST(TokensFile, ReadsNamedTokensWithTheirRoles) {
  const std::string path = tokens_file_with("good", R"({"format": "calstand-tokens/1", "tokens": [
      {"name": "display", "role": "read", "token": "display-0123456789abcdef"},
      {"name": "lab-op", "role": "operator", "token": "operator-0123456789abcdef"}]})");
  const auto tokens = load_tokens_file(path);
  ASSERT_EQ(tokens.size(), 2u);
  EXPECT_EQ(tokens[0].name, "display");
  EXPECT_EQ(tokens[0].role, Role::kRead);
  EXPECT_EQ(tokens[1].role, Role::kOperator);
  EXPECT_EQ(tokens[1].secret, "operator-0123456789abcdef");
  std::filesystem::remove(path);
}

TEST(TokensFile, RefusalsNameTheFileAndTheField) {
  auto error_of = [](const std::string& name, const std::string& text) {
    const std::string path = tokens_file_with(name, text);
    std::string what;
    try {
      load_tokens_file(path);
    } catch (const calstand::core::InputError& e) {
      EXPECT_EQ(e.where(), path);
      what = e.what();
    }
    std::filesystem::remove(path);
    return what;
  };
  const std::string prefix = R"({"format": "calstand-tokens/1", "tokens": [)";
  EXPECT_NE(error_of("short", prefix + R"({"name": "a", "role": "read", "token": "short"}]})")
                .find("tokens[0].token"),
            std::string::npos);
  EXPECT_NE(
      error_of("role", prefix + R"({"name": "a", "role": "admin", "token": "0123456789abcdef"}]})")
          .find("tokens[0].role"),
      std::string::npos);
  EXPECT_NE(
      error_of("name", prefix + R"({"name": "a b", "role": "read", "token": "0123456789abcdef"}]})")
          .find("tokens[0].name"),
      std::string::npos);
  EXPECT_NE(
      error_of("twice", prefix + R"({"name": "a", "role": "read", "token": "0123456789abcdef"},
      {"name": "a", "role": "operator", "token": "fedcba9876543210"}]})")
          .find("tokens[1].name: 'a' is given twice"),
      std::string::npos);
  EXPECT_NE(
      error_of("shared", prefix + R"({"name": "a", "role": "read", "token": "0123456789abcdef"},
      {"name": "b", "role": "operator", "token": "0123456789abcdef"}]})")
          .find("tokens[1].token"),
      std::string::npos);
}

TEST(TokensFile, TheLegacyTokenIsTheOperatorAndMayNotShareANameOrSecret) {
  ApiOptions o;
  o.token = "legacy-0123456789abcdef";
  ASSERT_EQ(o.all_tokens().size(), 1u);
  EXPECT_EQ(o.all_tokens()[0].name, kLegacyTokenName);
  EXPECT_EQ(o.all_tokens()[0].role, Role::kOperator);
  o.tokens = {{"operator", Role::kRead, "another-0123456789abcdef"}};
  EXPECT_THROW(o.validate(), calstand::core::InputError);
  o.tokens = {{"display", Role::kRead, "legacy-0123456789abcdef"}};
  EXPECT_THROW(o.validate(), calstand::core::InputError);
  o.tokens = {{"display", Role::kRead, "another-0123456789abcdef"}};
  EXPECT_NO_THROW(o.validate());
}

}  // namespace

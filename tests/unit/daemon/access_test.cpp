#include "daemon/api/access.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "daemon/api/api_server.hpp"

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
  EXPECT_NO_THROW(o.validate());
  o.port = 70000;
  EXPECT_THROW(o.validate(), calstand::core::InputError);
}

}  // namespace

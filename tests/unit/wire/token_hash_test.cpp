// Hashed bearer tokens (wire/token_hash.hpp): scrypt against RFC 7914's published test vector,
// a right secret accepted and every wrong one refused, and the stored form holding no secret.
#include "wire/token_hash.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "core/error.hpp"

namespace {

using calstand::wire::check_token_hash;
using calstand::wire::hash_token_secret;
using calstand::wire::new_token_secret;
using calstand::wire::token_id_of;
using calstand::wire::token_secret_matches;

std::string hex_of(const std::string& text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (unsigned char c : text) {
    out += kHex[c >> 4];
    out += kHex[c & 0x0f];
  }
  return out;
}

// RFC 7914 section 12, the second vector: scrypt("password", "NaCl", N = 1024, r = 8, p = 16,
// dkLen = 64). Written in the stored form, the check must accept exactly that password.
TEST(TokenHash, TheStoredFormChecksAsRfc7914sPublishedVector) {
  const std::string stored =
      "$scrypt$ln=10,r=8,p=16$" + hex_of("NaCl") +
      "$fdbabe1c9d3472007856e7190d01e9fe7c6ad7cbc8237830e77376634b3731622eaf30d92e22a3886ff109279"
      "d9830dac727afb94a83ee6d8360cbdfa2cc0640";
  EXPECT_TRUE(token_secret_matches("password", stored, "vector"));
  EXPECT_FALSE(token_secret_matches("passwore", stored, "vector"));
  EXPECT_FALSE(token_secret_matches("Password", stored, "vector"));
}

TEST(TokenHash, ARightSecretIsAcceptedAndWrongOnesRefused) {
  const auto made = new_token_secret();
  ASSERT_EQ(made.id.size(), 16u);
  ASSERT_EQ(made.secret.size(), 16u + 1u + 64u);
  EXPECT_EQ(token_id_of(made.secret), made.id);
  const std::string stored = hash_token_secret(made.secret);
  EXPECT_TRUE(token_secret_matches(made.secret, stored, "t"));
  std::string last_changed = made.secret;
  last_changed.back() = last_changed.back() == '0' ? '1' : '0';
  EXPECT_FALSE(token_secret_matches(last_changed, stored, "t"));
  EXPECT_FALSE(token_secret_matches(made.secret + "0", stored, "t"));
  EXPECT_FALSE(token_secret_matches(made.secret.substr(0, 40), stored, "t"));
  EXPECT_FALSE(token_secret_matches(new_token_secret().secret, stored, "t"));
  EXPECT_FALSE(token_secret_matches("", stored, "t"));
  // The stored form holds neither the secret nor its random part; a second hash of the same
  // secret differs (a fresh salt), and both check.
  EXPECT_EQ(stored.find(made.secret.substr(17)), std::string::npos);
  EXPECT_EQ(stored.rfind("$scrypt$ln=15,r=8,p=1$", 0), 0u) << stored;
  const std::string again = hash_token_secret(made.secret);
  EXPECT_NE(again, stored);
  EXPECT_TRUE(token_secret_matches(made.secret, again, "t"));
}

TEST(TokenHash, NewSecretsDoNotRepeat) {
  std::set<std::string> seen;
  for (int i = 0; i < 200; ++i) EXPECT_TRUE(seen.insert(new_token_secret().secret).second);
}

TEST(TokenHash, AMalformedStoredFormIsRefusedByWhere) {
  for (const std::string bad :
       {"", "plain-secret-0123456789", "$scrypt$ln=15,r=8$00$00", "$scrypt$ln=15,r=8,p=1$zz$00",
        "$scrypt$ln=40,r=8,p=1$0011223344556677$00112233445566778899aabbccddeeff",
        "$bcrypt$ln=15,r=8,p=1$0011223344556677$00112233445566778899aabbccddeeff"}) {
    try {
      check_token_hash(bad, "tokens.json: tokens[0].hash");
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const calstand::core::InputError& e) {
      EXPECT_EQ(e.where(), "tokens.json: tokens[0].hash") << bad;
    }
  }
}

}  // namespace

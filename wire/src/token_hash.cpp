#include "wire/token_hash.hpp"

#include <fmt/format.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/rand.h>

#include <array>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "core/error.hpp"

namespace calstand::wire {
namespace {

// scrypt's cost: N = 2^15, r = 8, p = 1 (32 MiB, ~0.1 s on a 2020s core). RFC 7914 section 2
// used N = 2^14 for interactive logins in 2009; one step up. The secrets are 256 random bits,
// so the cost guards a stolen file against nothing a guess could reach anyway: it is the
// standard's margin, paid once per secret and daemon (the daemon remembers a verified secret).
constexpr int kLogN = 15;
constexpr int kR = 8;
constexpr int kP = 1;
constexpr std::size_t kSaltBytes = 16;
constexpr std::size_t kKeyBytes = 32;
// The largest cost a stored hash may ask for (a file can raise it, within reason).
constexpr int kMaxLogN = 20;

std::string random_hex(std::size_t bytes) {
  std::vector<unsigned char> raw(bytes);
  if (RAND_bytes(raw.data(), static_cast<int>(raw.size())) != 1) {
    throw std::runtime_error("the random generator (OpenSSL RAND_bytes) failed");
  }
  std::string out;
  out.reserve(2 * bytes);
  for (unsigned char b : raw) out += fmt::format("{:02x}", b);
  return out;
}

bool hex_to_bytes(std::string_view hex, std::vector<unsigned char>& out) {
  if (hex.size() % 2 != 0) return false;
  out.clear();
  for (std::size_t i = 0; i < hex.size(); i += 2) {
    unsigned value = 0;
    const auto [end, ec] = std::from_chars(hex.data() + i, hex.data() + i + 2, value, 16);
    if (ec != std::errc() || end != hex.data() + i + 2) return false;
    out.push_back(static_cast<unsigned char>(value));
  }
  return true;
}

struct ParsedHash {
  int log_n = 0;
  int r = 0;
  int p = 0;
  std::vector<unsigned char> salt;
  std::vector<unsigned char> key;
};

ParsedHash parse_hash(std::string_view stored, const std::string& where) {
  const auto bad = [&](const std::string& why) {
    return core::InputError(where,
                            "not a token hash of `calstand token add` ($scrypt$ln=N,r=R,p=P"
                            "$SALT$KEY): " +
                                why);
  };
  constexpr std::string_view kPrefix = "$scrypt$";
  if (stored.substr(0, kPrefix.size()) != kPrefix) throw bad("it does not start with $scrypt$");
  std::string_view rest = stored.substr(kPrefix.size());
  std::array<std::string_view, 3> parts;
  for (std::size_t i = 0; i < 3; ++i) {
    const std::size_t cut = i < 2 ? rest.find('$') : rest.size();
    if (cut == std::string_view::npos) throw bad("it has fewer than three $-separated parts");
    parts[i] = rest.substr(0, cut);
    rest = i < 2 ? rest.substr(cut + 1) : std::string_view{};
  }
  ParsedHash h;
  if (std::sscanf(std::string(parts[0]).c_str(), "ln=%d,r=%d,p=%d", &h.log_n, &h.r, &h.p) != 3) {
    throw bad("its parameters are not ln=N,r=R,p=P");
  }
  if (h.log_n < 10 || h.log_n > kMaxLogN || h.r < 1 || h.r > 32 || h.p < 1 || h.p > 16) {
    throw bad(fmt::format("parameters ln={},r={},p={} are outside ln 10..{}, r 1..32, p 1..16",
                          h.log_n, h.r, h.p, kMaxLogN));
  }
  if (!hex_to_bytes(parts[1], h.salt) || h.salt.size() < 4) throw bad("the salt is not hex");
  if (!hex_to_bytes(parts[2], h.key) || h.key.size() < 16) throw bad("the key is not hex");
  return h;
}

std::vector<unsigned char> derive(std::string_view secret, const std::vector<unsigned char>& salt,
                                  int log_n, int r, int p, std::size_t key_bytes) {
  std::vector<unsigned char> key(key_bytes);
  const std::uint64_t n = std::uint64_t{1} << log_n;
  // scrypt needs 128 * N * r * p bytes and a little more; allow twice that.
  const std::uint64_t max_mem =
      256 * n * static_cast<std::uint64_t>(r) * static_cast<std::uint64_t>(p);
  if (EVP_PBE_scrypt(secret.data(), secret.size(), salt.data(), salt.size(), n,
                     static_cast<std::uint64_t>(r), static_cast<std::uint64_t>(p), max_mem,
                     key.data(), key.size()) != 1) {
    throw std::runtime_error("scrypt (OpenSSL EVP_PBE_scrypt) failed");
  }
  return key;
}

std::string to_hex(const std::vector<unsigned char>& bytes) {
  std::string out;
  out.reserve(2 * bytes.size());
  for (unsigned char b : bytes) out += fmt::format("{:02x}", b);
  return out;
}

}  // namespace

NewTokenSecret new_token_secret() {
  NewTokenSecret t;
  t.id = random_hex(8);
  t.secret = t.id + "." + random_hex(32);
  return t;
}

std::string_view token_id_of(std::string_view presented) {
  const std::size_t dot = presented.find('.');
  if (dot == std::string_view::npos) return {};
  return presented.substr(0, dot);
}

std::string hash_token_secret(std::string_view secret) {
  std::vector<unsigned char> salt;
  hex_to_bytes(random_hex(kSaltBytes), salt);
  const auto key = derive(secret, salt, kLogN, kR, kP, kKeyBytes);
  return fmt::format("$scrypt$ln={},r={},p={}${}${}", kLogN, kR, kP, to_hex(salt), to_hex(key));
}

void check_token_hash(std::string_view stored, const std::string& where) {
  parse_hash(stored, where);
}

bool token_secret_matches(std::string_view presented, std::string_view stored,
                          const std::string& where) {
  const ParsedHash h = parse_hash(stored, where);
  const auto key = derive(presented, h.salt, h.log_n, h.r, h.p, h.key.size());
  return CRYPTO_memcmp(key.data(), h.key.data(), key.size()) == 0;
}

}  // namespace calstand::wire

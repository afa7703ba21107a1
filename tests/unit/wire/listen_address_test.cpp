#include "wire/listen_address.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"

namespace {

using calstand::core::InputError;
using calstand::wire::parse_listen_address;

TEST(ListenAddress, HostAndPort) {
  EXPECT_EQ(parse_listen_address("127.0.0.1:8765"), std::make_pair(std::string("127.0.0.1"), 8765));
  EXPECT_EQ(parse_listen_address("[::1]:0"), std::make_pair(std::string("::1"), 0));
  EXPECT_EQ(parse_listen_address("localhost:65535"),
            std::make_pair(std::string("localhost"), 65535));
}

TEST(ListenAddress, RefusesWhatIsNotHostColonPort) {
  EXPECT_THROW(parse_listen_address("127.0.0.1"), InputError);
  EXPECT_THROW(parse_listen_address("127.0.0.1:http"), InputError);
  EXPECT_THROW(parse_listen_address("127.0.0.1:80x"), InputError);
  EXPECT_THROW(parse_listen_address(":80"), InputError);
  EXPECT_THROW(parse_listen_address("h:"), InputError);
  EXPECT_THROW(parse_listen_address("h:99999"), InputError);
  EXPECT_THROW(parse_listen_address("h:-1"), InputError);
}

TEST(ListenAddress, TheErrorNamesTheOptionAndTheText) {
  try {
    parse_listen_address("localhost:http", "--daemon");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "--daemon");
    EXPECT_NE(std::string(e.what()).find("'http' is not a port"), std::string::npos) << e.what();
  }
  try {
    parse_listen_address("nowhere");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "--listen");
  }
}

TEST(DaemonAddress, SchemeChoosesTls) {
  using calstand::wire::parse_daemon_address;
  const auto plain = parse_daemon_address("10.0.0.5:8765", "--daemon");
  EXPECT_FALSE(plain.tls);
  EXPECT_EQ(plain.url(), "http://10.0.0.5:8765");
  const auto tls = parse_daemon_address("https://station.lab:8443/", "--daemon");
  EXPECT_TRUE(tls.tls);
  EXPECT_EQ(tls.host, "station.lab");
  EXPECT_EQ(tls.port, 8443);
  EXPECT_EQ(tls.url(), "https://station.lab:8443");
  EXPECT_EQ(parse_daemon_address("https://[::1]:9", "--daemon").url(), "https://[::1]:9");
  EXPECT_TRUE(parse_daemon_address("h:1", "--daemon", true).tls);          // a CA file was given
  EXPECT_FALSE(parse_daemon_address("http://h:1", "--daemon", true).tls);  // said so
  EXPECT_THROW(parse_daemon_address("ftp://h:1", "--daemon"), InputError);
  EXPECT_THROW(parse_daemon_address("https://h", "--daemon"), InputError);
}

}  // namespace

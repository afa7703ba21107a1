#include "fleet/central_address.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.hpp"

namespace calstand::fleet {
namespace {

std::string input_error(const std::string& url, const std::string& password_file = "") {
  try {
    parse_central_address(url, password_file, "--to");
  } catch (const core::InputError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(CentralAddress, APasswordInTheUrlIsRefusedSayingWhy) {
  const std::string why = input_error("postgresql://station:s3cret@fleet.example.com/fleet");
  EXPECT_TRUE(contains(why, "--to: the address holds a password")) << why;
  EXPECT_TRUE(contains(why, "/proc/PID/cmdline")) << why;
  EXPECT_FALSE(contains(why, "s3cret")) << "the refusal repeats the secret: " << why;
  // The keyword form and the query-parameter form alike.
  EXPECT_TRUE(contains(input_error("host=db user=a password=x dbname=f"), "holds a password"));
  EXPECT_TRUE(contains(input_error("postgresql://a@db/f?password=x"), "holds a password"));
}

TEST(CentralAddress, AServerOffThisMachineGetsTlsAndAnUnencryptedModeIsRefused) {
  const CentralAddress remote =
      parse_central_address("postgresql://a@db.example.com/f", "", "--to");
  EXPECT_FALSE(remote.local);
  EXPECT_TRUE(contains(remote.conninfo, "sslmode='require'")) << remote.conninfo;
  const CentralAddress verified =
      parse_central_address("postgresql://a@db.example.com/f?sslmode=verify-full", "", "--to");
  EXPECT_TRUE(contains(verified.conninfo, "sslmode='verify-full'")) << verified.conninfo;
  for (const char* mode : {"disable", "allow", "prefer"}) {
    const std::string why = input_error(std::string("postgresql://a@10.0.0.5/f?sslmode=") + mode);
    EXPECT_TRUE(contains(why, std::string("sslmode=") + mode + " to 10.0.0.5")) << why;
    EXPECT_TRUE(contains(why, "needs TLS")) << why;
  }
}

TEST(CentralAddress, ALocalServerNeedsNoTls) {
  for (const char* url : {"postgresql://a@localhost/f", "postgresql://a@127.0.0.1:5433/f",
                          "postgresql://a@/f?host=/var/run/postgresql", "postgresql:///f"}) {
    const CentralAddress local = parse_central_address(url, "", "--to");
    EXPECT_TRUE(local.local) << url;
    EXPECT_FALSE(contains(local.conninfo, "sslmode")) << url << ": " << local.conninfo;
  }
  // One remote host in a failover list makes the whole list remote.
  EXPECT_FALSE(parse_central_address("postgresql://a@localhost,db2/f", "", "--to").local);
}

TEST(CentralAddress, APasswordFileMustExistAndBePrivate) {
  const std::string dir = ::testing::TempDir() + "central-address-" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  const std::string file = dir + "/pgpass";
  std::ofstream(file) << "*:*:*:a:pw\n";
  ::chmod(file.c_str(), 0644);
  std::string why = input_error("postgresql://a@localhost/f", file);
  EXPECT_TRUE(contains(why, "--password-file " + file +
                                ": readable by group or others (mode "
                                "0644)"))
      << why;
  ::chmod(file.c_str(), 0600);
  const CentralAddress ok = parse_central_address("postgresql://a@localhost/f", file, "--to");
  EXPECT_TRUE(contains(ok.conninfo, "passfile='" + file + "'")) << ok.conninfo;
  EXPECT_EQ(ok.display, "a@localhost/f");
  why = input_error("postgresql://a@localhost/f", dir + "/missing");
  EXPECT_TRUE(contains(why, "no such file")) << why;
  std::filesystem::remove_all(dir);
}

TEST(CentralAddress, AMalformedUrlNamesTheOption) {
  const std::string why = input_error("postgresql://a@[broken/f");
  EXPECT_TRUE(contains(why, "--to: not a PostgreSQL connection URL")) << why;
  EXPECT_TRUE(contains(input_error(""), "--to: empty address"));
}

}  // namespace
}  // namespace calstand::fleet

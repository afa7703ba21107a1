#include "daemon/api/ustar_writer.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace {

using calstand::daemon::api::UstarWriter;

std::string run(const std::string& command) {
  FILE* pipe = popen(command.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf{};
  while (std::size_t n = fread(buf.data(), 1, buf.size(), pipe)) out.append(buf.data(), n);
  pclose(pipe);
  return out;
}

TEST(UstarWriter, GnuTarReadsBackEveryFileExactly) {
  UstarWriter tar;
  const std::string big(1500, 'x');  // spans blocks, padded
  tar.add_file("run-7/meta.json", "{\"format\": \"calstand-import/1\"}\n", 1700000000);
  tar.add_file("run-7/samples.csv", big);
  tar.add_file("run-7/empty.txt", "");
  const std::string archive = std::move(tar).finish();
  EXPECT_EQ(archive.size() % 512, 0u);

  const auto path =
      std::filesystem::temp_directory_path() / ("ustar-test-" + std::to_string(getpid()) + ".tar");
  std::ofstream(path, std::ios::binary) << archive;
  EXPECT_EQ(run("tar -tf " + path.string()),
            "run-7/meta.json\nrun-7/samples.csv\nrun-7/empty.txt\n");
  EXPECT_EQ(run("tar -xOf " + path.string() + " run-7/meta.json"),
            "{\"format\": \"calstand-import/1\"}\n");
  EXPECT_EQ(run("tar -xOf " + path.string() + " run-7/samples.csv"), big);
  std::filesystem::remove(path);
}

TEST(UstarWriter, RefusesNamesThatEscapeOrDoNotFit) {
  UstarWriter tar;
  EXPECT_THROW(tar.add_file("/etc/passwd", "x"), std::invalid_argument);
  EXPECT_THROW(tar.add_file("a/../../b", "x"), std::invalid_argument);
  EXPECT_THROW(tar.add_file(std::string(101, 'a'), "x"), std::invalid_argument);
  EXPECT_THROW(tar.add_file("", "x"), std::invalid_argument);
}

// A file of 8 GiB or more (a long run's CSV) does not fit the octal size field: its header
// says the size in base-256, which GNU tar reads. The archive is a sparse file: no disk used.
TEST(UstarWriter, SizesOfEightGibibytesAndMoreAreWrittenSoTarReadsThem) {
  const std::uint64_t size = (std::uint64_t{9} << 30) + 123;  // 9 GiB and a bit
  const std::string header =
      calstand::daemon::api::ustar_header("run-1/samples.csv", size, 1700000000);
  ASSERT_EQ(header.size(), 512u);
  const auto path =
      std::filesystem::temp_directory_path() / ("ustar-big-" + std::to_string(getpid()) + ".tar");
  std::ofstream(path, std::ios::binary) << header;
  std::filesystem::resize_file(path,
                               512 + size + calstand::daemon::api::ustar_padding(size) + 1024);
  const std::string listing = run("tar -tvf " + path.string() + " 2>&1");
  std::filesystem::remove(path);
  EXPECT_NE(listing.find(std::to_string(size)), std::string::npos) << listing;
  EXPECT_NE(listing.find("run-1/samples.csv"), std::string::npos) << listing;
}

}  // namespace

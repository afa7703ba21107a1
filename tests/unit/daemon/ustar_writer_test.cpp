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

  const auto path = std::filesystem::temp_directory_path() / ("ustar-test-" + std::to_string(getpid()) + ".tar");
  std::ofstream(path, std::ios::binary) << archive;
  EXPECT_EQ(run("tar -tf " + path.string()), "run-7/meta.json\nrun-7/samples.csv\nrun-7/empty.txt\n");
  EXPECT_EQ(run("tar -xOf " + path.string() + " run-7/meta.json"), "{\"format\": \"calstand-import/1\"}\n");
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

}  // namespace

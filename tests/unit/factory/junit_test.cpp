// The JUnit XML of an acceptance, read back by an XML parser that is not ours (python3's
// xml.etree): well formed, one suite per unit, one case per check, failures for fail and
// indeterminate, markup in names escaped.
#include "factory/junit.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace calstand::analysis {
namespace {

AcceptanceCheck junit_check(const std::string& name, Verdict verdict, double value) {
  AcceptanceCheck c;
  c.check = name;
  c.kind = "parameter";
  c.value = value;
  c.sigma = 0.5;
  c.limit = Bounds{10.0, std::nullopt, std::nullopt};
  c.unit = "ppm";
  c.verdict = verdict;
  c.reason = "because <reasons> & \"quotes\"";
  return c;
}

AcceptanceOutcome junit_outcome() {
  AcceptanceOutcome o;
  o.run = 7;
  o.spec.name = "spec <A&B>";
  o.spec.sha256 = std::string(64, 'f');
  UnitAcceptance a;
  a.device = "imu0";
  a.serial = "SN1";
  a.calibration = 3;
  a.checks = {junit_check("gyro_scale.x", Verdict::kPass, 1.0),
              junit_check("gyro_scale.y", Verdict::kFail, 12.0),
              junit_check("gyro_scale.z", Verdict::kIndeterminate, 9.8)};
  a.verdict = Verdict::kFail;
  UnitAcceptance b;
  b.device = "imu1";
  b.calibration = 4;
  b.checks = {junit_check("gyro_scale.x", Verdict::kPass, 2.0)};
  b.verdict = Verdict::kPass;
  o.units = {a, b};
  return o;
}

// Runs python3 on `script` with `xml_path` as its argument; its stdout.
std::string run_python(const std::string& script, const std::string& xml_path) {
  const std::string command = "python3 -c '" + script + "' " + xml_path + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return "popen failed";
  std::string out;
  std::array<char, 4096> buf{};
  while (std::size_t n = fread(buf.data(), 1, buf.size(), pipe)) out.append(buf.data(), n);
  const int status = pclose(pipe);
  return status == 0 ? out : "python3 failed: " + out;
}

TEST(JUnit, ParsesBackWithOneSuitePerUnitAndOneCasePerCheck) {
  if (std::system("python3 -c 'import xml.etree.ElementTree' >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "python3 is not installed";
  }
  const std::string path =
      ::testing::TempDir() + "calstand-junit-" + std::to_string(::getpid()) + ".xml";
  std::ofstream(path) << junit_xml(junit_outcome());
  // One line per suite: name tests failures, then per case: name, failure type or "-".
  const std::string script =
      "import sys, xml.etree.ElementTree as ET\n"
      "root = ET.parse(sys.argv[1]).getroot()\n"
      "print(root.tag, root.get(\"tests\"), root.get(\"failures\"), root.get(\"name\"))\n"
      "for s in root.findall(\"testsuite\"):\n"
      "  props = {p.get(\"name\"): p.get(\"value\") for p in s.find(\"properties\")}\n"
      "  print(\"suite\", s.get(\"name\"), s.get(\"tests\"), s.get(\"failures\"), "
      "props[\"verdict\"], props[\"spec\"])\n"
      "  for c in s.findall(\"testcase\"):\n"
      "    f = c.find(\"failure\")\n"
      "    print(\" case\", c.get(\"name\"), c.get(\"classname\"), "
      "f.get(\"type\") if f is not None else \"-\")\n";
  const std::string out = run_python(script, path);
  std::filesystem::remove(path);
  EXPECT_EQ(out,
            "testsuites 4 2 calstand accept run 7 against spec <A&B>\n"
            "suite imu0 SN1 3 2 fail spec <A&B>\n"
            " case gyro_scale.x calstand.accept.imu0 -\n"
            " case gyro_scale.y calstand.accept.imu0 fail\n"
            " case gyro_scale.z calstand.accept.imu0 indeterminate\n"
            "suite imu1 1 0 pass spec <A&B>\n"
            " case gyro_scale.x calstand.accept.imu1 -\n");
}

TEST(JUnit, AFailureSaysValueSigmaLimitAndWhy) {
  const std::string xml = junit_xml(junit_outcome());
  EXPECT_EQ(xml.rfind("<?xml version=\"1.0\" encoding=\"UTF-8\"?>", 0), 0u);
  EXPECT_NE(xml.find("value 12, sigma 0.5, limit |v| &lt;= 10 ppm, verdict fail: because "
                     "&lt;reasons&gt; &amp; &quot;quotes&quot;"),
            std::string::npos)
      << xml;
  EXPECT_EQ(xml.find("<reasons>"), std::string::npos);
}

}  // namespace
}  // namespace calstand::analysis

#include "render/gnuplot_svg.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "core/error.hpp"

namespace {

using calstand::analysis::gnuplot_quote;

TEST(GnuplotQuote, LeavesNoBackquoteForGnuplotToRun) {
  EXPECT_EQ(gnuplot_quote("plain"), "\"plain\"");
  EXPECT_EQ(gnuplot_quote("say \"hi\"\\"), R"("say \"hi\"\\")");
  EXPECT_EQ(gnuplot_quote("a`id`b"), R"("a\140id\140b")");
  EXPECT_EQ(gnuplot_quote("two\nlines"), R"("two\nlines")");
}

// A step label (from a procedure a client sent) reaches the report's plots as a title: it must
// be drawn as text, never run by the shell gnuplot starts for backquotes.
TEST(GnuplotSvg, TextWithBackquotesIsDrawnNotRun) {
  try {
    calstand::analysis::find_gnuplot();
  } catch (const calstand::core::InputError&) {
    GTEST_SKIP() << "gnuplot is not installed";
  }
  const auto marker = std::filesystem::temp_directory_path() /
                      ("calstand-gnuplot-injected-" + std::to_string(::getpid()));
  std::filesystem::remove(marker);
  const std::string label = "step `touch " + marker.string() + "` $(id)";
  const std::string script =
      "set terminal svg size 400,300 noenhanced\n$d << EOD\n1 2\n2 3\nEOD\n" +
      std::string("set title ") + gnuplot_quote(label) + "\nplot $d using 1:2 with points title " +
      gnuplot_quote(label) + "\n";
  const std::string svg = calstand::analysis::gnuplot_svg(script, "t", "injection");
  EXPECT_FALSE(std::filesystem::exists(marker)) << "gnuplot ran the label through the shell";
  EXPECT_NE(svg.find("`touch"), std::string::npos) << "the label is drawn as written";
  std::filesystem::remove(marker);
}

}  // namespace

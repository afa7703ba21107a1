#include "render/gnuplot_svg.hpp"

#include <fmt/format.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>

#include "core/error.hpp"
#include "core/text.hpp"
#include "render/markup_escape.hpp"

namespace calstand::analysis {
namespace {

// A private temporary directory, removed with everything in it.
class TempDir {
 public:
  TempDir() {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "calstand-plot-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw std::runtime_error("cannot create a temporary directory for gnuplot in " +
                               std::filesystem::temp_directory_path().string());
    }
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);  // never throws
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// gnuplot's SVG as an inline element of an HTML page (see gnuplot_svg()).
std::string inline_svg(std::string svg, const std::string& prefix, const std::string& title) {
  const auto start = svg.find("<svg");
  if (start == std::string::npos) {
    throw core::InputError("gnuplot", "produced no SVG (is its svg terminal available?)");
  }
  svg.erase(0, start);
  svg = std::regex_replace(svg, std::regex(R"(\s+xmlns(:\w+)?="[^"]*")"), "");
  svg = std::regex_replace(svg, std::regex(R"(xlink:href=)"), "href=");
  svg = std::regex_replace(svg, std::regex(R"(\bid=(['"]))"), "id=$1" + prefix + "-");
  svg = std::regex_replace(svg, std::regex(R"(href=(['"])#)"), "href=$1#" + prefix + "-");
  svg = std::regex_replace(svg, std::regex(R"(url\(#)"), "url(#" + prefix + "-");
  svg = std::regex_replace(svg, std::regex(R"(<title>Gnuplot</title>)"),
                           "<title>" + html_escape(title) + "</title>");
  svg = std::regex_replace(svg, std::regex(R"(<desc>[^<]*</desc>\s*)"), "");
  return svg;
}

}  // namespace

std::string find_gnuplot() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    if (dir.empty()) continue;
    const std::filesystem::path candidate = std::filesystem::path(dir) / "gnuplot";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
  }
  throw core::InputError("gnuplot",
                         "not found on PATH; the report draws its plots with gnuplot "
                         "(Debian: apt-get install gnuplot-nox)");
}

std::string gnuplot_svg(const std::string& script, const std::string& id_prefix,
                        const std::string& title) {
  const std::string gnuplot = find_gnuplot();
  const TempDir dir;
  const auto script_file = dir.path() / "plot.gp";
  const auto svg_file = dir.path() / "plot.svg";
  const auto err_file = dir.path() / "stderr.txt";
  {
    std::ofstream out(script_file);
    if (!(out << script) || !out.flush()) {
      throw std::runtime_error("cannot write the gnuplot script to " + script_file.string());
    }
  }
  const std::string command = core::shell_quote(gnuplot) + " " +
                              core::shell_quote(script_file.string()) + " >" +
                              core::shell_quote(svg_file.string()) + " 2>" +
                              core::shell_quote(err_file.string()) + " </dev/null";
  const int status = std::system(command.c_str());
  std::string err = read_file(err_file);
  while (!err.empty() && std::isspace(static_cast<unsigned char>(err.back()))) err.pop_back();
  if (status != 0) {
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    throw core::InputError("gnuplot",
                           fmt::format("{} failed (exit {}) drawing '{}'{}", gnuplot, code, title,
                                       err.empty() ? std::string() : ": " + err.substr(0, 600)));
  }
  return inline_svg(read_file(svg_file), id_prefix, title);
}

std::string gnuplot_quote(std::string_view text) {
  std::string out = "\"";
  for (char c : text) {
    // gnuplot runs `text in backquotes` through the shell even inside double quotes, before
    // it reads escapes: a step label or device name must never get there, so a backquote is
    // written as its octal escape, which gnuplot turns back into the character afterwards.
    if (c == '`') {
      out += "\\140";
      continue;
    }
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out + "\"";
}

std::string data_text(std::string_view text) {
  std::string out = "\"";
  for (char c : text) out += c == '"' ? '\'' : (c == '\n' ? ' ' : c);
  return out + "\"";
}

std::string data_block(std::string_view name, const std::vector<std::string>& rows) {
  std::string out = fmt::format("${} << EOD\n", name);
  for (const auto& r : rows) out += r + "\n";
  return out + "EOD\n";
}

std::string gp_number(double value) {
  return std::isfinite(value) ? fmt::format("{}", value) : std::string("NaN");
}

std::string svg_terminal(int width, int height) {
  return fmt::format(
      "set terminal svg size {},{} dynamic noenhanced font 'Helvetica,12' background '#ffffff'\n"
      "set border lw 1 lc rgb '#555555'\n"
      "set grid lc rgb '#e4e4e4' lw 1\n"
      "set tics textcolor rgb '#333333'\n",
      width, height);
}

std::string horizontal_line(double y, const char* rgb, int dash) {
  return fmt::format(
      "set arrow from graph 0, first {0} to graph 1, first {0} nohead dt {1} lw 1.5 lc rgb '{2}' "
      "front\n",
      gp_number(y), dash, rgb);
}

}  // namespace calstand::analysis

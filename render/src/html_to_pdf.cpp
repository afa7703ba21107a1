#include "render/html_to_pdf.hpp"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "core/text.hpp"

namespace calstand::analysis {
namespace {

std::string first_bytes(const std::filesystem::path& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string out(n, '\0');
  in.read(out.data(), static_cast<std::streamsize>(n));
  out.resize(static_cast<std::size_t>(in.gcount()));
  return out;
}

}  // namespace

std::string find_chromium() {
  const char* path = std::getenv("PATH");
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    std::stringstream dirs(path ? path : "");
    for (std::string dir; std::getline(dirs, dir, ':');) {
      if (dir.empty()) continue;
      const std::filesystem::path candidate = std::filesystem::path(dir) / name;
      if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    }
  }
  throw core::InputError("chromium",
                         "not found on PATH; a PDF is printed by headless Chromium (Debian: "
                         "apt-get install chromium), or write the HTML and print it yourself");
}

void html_to_pdf(const std::string& html, const std::string& pdf_path) {
  const std::string chromium = find_chromium();
  const std::filesystem::path target = std::filesystem::absolute(pdf_path);
  const std::filesystem::path partial = target.string() + ".partial";
  // Chromium reads the page from a file beside the target (a profile of its own in a temporary
  // folder, so that a user's running browser is not touched).
  const std::filesystem::path page = target.string() + ".partial.html";
  const std::filesystem::path profile =
      std::filesystem::temp_directory_path() / ("calstand-chromium-" + std::to_string(::getpid()));
  {
    std::ofstream out(page, std::ios::binary | std::ios::trunc);
    if (!(out << html) || !out.flush()) {
      throw core::InputError(pdf_path, "cannot write beside it: " + page.string());
    }
  }
  // --no-sandbox: a station often runs as root, where Chromium's sandbox refuses to start.
  const std::string command =
      "timeout 120 " + core::shell_quote(chromium) +
      " --headless --no-sandbox --disable-gpu --no-pdf-header-footer --user-data-dir=" +
      core::shell_quote(profile.string()) +
      " --print-to-pdf=" + core::shell_quote(partial.string()) + " " +
      core::shell_quote("file://" + page.string()) + " >/dev/null 2>&1 </dev/null";
  const int status = std::system(command.c_str());
  std::error_code ignored;
  std::filesystem::remove(page, ignored);
  std::filesystem::remove_all(profile, ignored);
  if (status != 0 || first_bytes(partial, 5) != "%PDF-") {
    std::filesystem::remove(partial, ignored);
    throw core::InputError(
        "chromium", "printing the page to PDF failed (exit status " + std::to_string(status) + ")");
  }
  std::filesystem::rename(partial, target);
}

}  // namespace calstand::analysis

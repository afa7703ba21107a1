#include "core/file_output.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/error.hpp"

namespace calstand::core {

void write_file_whole(const std::string& path, std::string_view text) {
  const std::string tmp = path + ".tmp." + std::to_string(static_cast<long>(::getpid()));
  struct RemoveUnlessRenamed {
    const std::string& path;
    bool renamed = false;
    ~RemoveUnlessRenamed() {
      std::error_code ignored;
      if (!renamed) std::filesystem::remove(path, ignored);
    }
  } guard{tmp};
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f || !f.write(text.data(), static_cast<std::streamsize>(text.size())) || !f.flush()) {
      throw InputError(path, "cannot write the file");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw InputError(path, "cannot write the file: " + ec.message());
  guard.renamed = true;
}

}  // namespace calstand::core

#include "commands.hpp"

namespace calstand::cli {

void register_allan(CLI::App& app) { (void)app; }

}  // namespace calstand::cli

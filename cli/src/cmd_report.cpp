#include "commands.hpp"

namespace calstand::cli {

void register_report(CLI::App& app) { (void)app; }

}  // namespace calstand::cli

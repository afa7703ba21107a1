#include "commands.hpp"

namespace calstand::cli {

void register_fit(CLI::App& app) { (void)app; }

}  // namespace calstand::cli

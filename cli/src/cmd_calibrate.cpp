#include "commands.hpp"

namespace calstand::cli {

void register_calibrate(CLI::App& app) { (void)app; }

}  // namespace calstand::cli

// placeholder: being written
#include "commands.hpp"
namespace calstand::cli { void register_units(CLI::App&) {} }

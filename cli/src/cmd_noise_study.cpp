// placeholder: being written
#include "commands.hpp"
namespace calstand::cli { void register_noise_study(CLI::App&) {} }

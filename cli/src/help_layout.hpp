#pragma once

#include <CLI/CLI.hpp>

namespace calstand::cli {

/// Lays out `calstand --help` by task (issue 31): the subcommands in groups in the order a
/// person meets them (start here, run a station, analyse a run, the loop, without a table, the
/// factory line, the fleet, devices, simulation), and one example under each subcommand's own
/// help. Call it after every register_x(app). A subcommand missing from the table in
/// help_layout.cpp is listed under "Other" (and the CLI test fails), so a new one is seen.
void arrange_help(CLI::App& app);

}  // namespace calstand::cli

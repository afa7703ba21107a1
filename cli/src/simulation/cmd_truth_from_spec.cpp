// `calstand truth-from-spec`: draws one simulated IMU from a datasheet-style spec sheet and
// writes its truth file (every error parameter and noise figure the simulator will use).
#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <system_error>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/file_output.hpp"
#include "core/json_schema.hpp"
#include "sim/imu_truth.hpp"
#include "sim/spec_sheet.hpp"

namespace calstand::cli {
namespace {

struct TruthFromSpecOptions {
  std::string spec;
  std::uint64_t seed = 1;
  std::string out;
};

void write_truth_from_spec(const TruthFromSpecOptions& opt) {
  nlohmann::json spec;
  std::string name = opt.spec;
  if (auto builtin = sim::builtin_spec(opt.spec)) {
    spec = *builtin;
    name = "<built-in " + opt.spec + ">";
  } else if (std::filesystem::exists(opt.spec)) {
    spec = core::read_json_file(opt.spec);
  } else {
    std::string known;
    for (const auto& n : sim::builtin_spec_names()) known += (known.empty() ? "" : ", ") + n;
    throw core::InputError(opt.spec, fmt::format("neither a file nor a built-in spec sheet "
                                                 "(built-in: {})",
                                                 known));
  }
  const sim::ImuTruth truth = sim::truth_from_spec(spec, name, opt.seed);
  const std::string text = sim::imu_truth_to_json(truth).dump(2) + "\n";
  if (opt.out.empty()) {
    fmt::print("{}", text);
    return;
  }
  core::write_file_whole(opt.out, text);
}

}  // namespace

void register_truth_from_spec(CLI::App& app) {
  auto opt = std::make_shared<TruthFromSpecOptions>();
  CLI::App* cmd = app.add_subcommand(
      "truth-from-spec",
      "Draw one simulated IMU from a spec sheet (built-in name or calstand-spec/1 file) and "
      "print or write its truth file (calstand-truth/1)");
  cmd->add_option("spec", opt->spec, "Built-in spec name (ln200, adis16488) or spec-sheet file")
      ->required();
  cmd->add_option("--seed", opt->seed, "Seed of the draw")->capture_default_str();
  cmd->add_option("--out", opt->out, "Write the truth file here instead of stdout");
  cmd->callback([opt] { write_truth_from_spec(*opt); });
}

}  // namespace calstand::cli

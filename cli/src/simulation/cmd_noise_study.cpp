// calstand noise-study: exercise 2 of the seed notes (simulation of common random processes).
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <system_error>

#include "commands.hpp"
#include "core/error.hpp"
#include "sim/noise_study.hpp"

namespace calstand::cli {

namespace {

// The options arrive as text and are converted here rather than by CLI11, so that every bad
// value is an InputError naming the option (exit code 2), like the other commands' input.
struct NoiseStudyArgs {
  std::string runs = "100";
  std::string seed = "1";
  std::string duration = "3600";
  bool json = false;
};

template <typename Int>
Int parse_integer(const std::string& text, const char* option) {
  Int value{};
  const char* first = text.data();
  const char* last = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (ec != std::errc() || ptr != last || text.empty()) {
    throw core::InputError(option, fmt::format("expected an integer, got '{}'", text));
  }
  return value;
}

double parse_number(const std::string& text, const char* option) {
  double value = 0.0;
  const char* first = text.data();
  const char* last = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (ec != std::errc() || ptr != last || text.empty() || !std::isfinite(value)) {
    throw core::InputError(option, fmt::format("expected a finite number, got '{}'", text));
  }
  return value;
}

sim::NoiseStudyOptions to_options(const NoiseStudyArgs& args) {
  sim::NoiseStudyOptions o;
  const long long runs = parse_integer<long long>(args.runs, "--runs");
  if (runs < 2 || runs > 1'000'000) {
    throw core::InputError("--runs", fmt::format("must be in [2, 1000000], got {}", runs));
  }
  o.runs = static_cast<int>(runs);
  if (!args.seed.empty() && args.seed.front() == '-') {
    throw core::InputError("--seed",
                           fmt::format("must be a non-negative integer, got '{}'", args.seed));
  }
  o.seed = parse_integer<std::uint64_t>(args.seed, "--seed");
  o.duration_s = parse_number(args.duration, "--duration");
  if (o.duration_s * o.sample_rate_hz < 1.0 || o.duration_s > 1e6) {
    throw core::InputError("--duration", fmt::format("must be in [{}, 1e6] s, got {}",
                                                     1.0 / o.sample_rate_hz, args.duration));
  }
  // A study is single threaded at some 1e8 samples per second: 1e6 run-seconds at 1 kHz is
  // about ten minutes. More is a typo, not a study.
  constexpr double kMaxRunSeconds = 1e6;
  if (static_cast<double>(o.runs) * o.duration_s > kMaxRunSeconds) {
    throw core::InputError("--runs/--duration",
                           fmt::format("{} runs of {} s is {:g} run-seconds; at most {:g} "
                                       "(reduce --runs or --duration)",
                                       o.runs, o.duration_s,
                                       static_cast<double>(o.runs) * o.duration_s, kMaxRunSeconds));
  }
  // A shorter run cannot show the later walk times; show the ones that fit, or the run's end.
  std::vector<double> walk_times;
  for (const double t : o.walk_times_s) {
    if (t <= o.duration_s) walk_times.push_back(t);
  }
  if (walk_times.empty()) walk_times.push_back(o.duration_s);
  o.walk_times_s = walk_times;
  return o;
}

double ratio(double simulated, double theory) {
  return theory != 0.0 ? simulated / theory : std::nan("");
}

void print_json(const sim::NoiseStudyResult& r) {
  // ordered_json keeps the keys in the documented order instead of sorting them.
  nlohmann::ordered_json out;
  out["white"] = nlohmann::ordered_json::array();
  for (const auto& row : r.white) {
    out["white"].push_back({{"cutoff_hz", row.cutoff_hz},
                            {"rms", row.rms},
                            {"theory", row.theory},
                            {"theory_analog", row.theory_analog}});
  }
  out["random_walk"] = nlohmann::ordered_json::array();
  for (const auto& row : r.random_walk) {
    out["random_walk"].push_back({{"t_s", row.t_s}, {"sigma", row.sigma}, {"theory", row.theory}});
  }
  out["gauss_markov"] = nlohmann::ordered_json::array();
  for (const auto& row : r.gauss_markov) {
    out["gauss_markov"].push_back({{"tau_s", row.tau_s},
                                   {"sigma", row.sigma},
                                   {"theory", row.theory},
                                   {"q", row.q},
                                   {"within_run_sigma", row.within_run_sigma}});
  }
  std::cout << out.dump(2) << "\n";
}

void print_tables(const sim::NoiseStudyOptions& o, const sim::NoiseStudyResult& r) {
  std::cout << fmt::format(
      "Noise study: {} runs of {} s at {} Hz, raw white noise sigma {} deg/h per sample, seed {}\n",
      o.runs, o.duration_s, o.sample_rate_hz, o.white_sigma_dph, o.seed);

  std::cout << fmt::format(
      "\nBand-limited white noise (digital Butterworth order {}; first row unfiltered)\n"
      "theory = sigma * sqrt(sum h_k^2) of the digital filter (exact); "
      "analog = sigma * sqrt(ENBW / (fs/2)) of the analog prototype\n",
      o.filter_order);
  std::cout << fmt::format("{:>12} {:>14} {:>15} {:>8} {:>15}\n", "cutoff [Hz]", "rms [deg/h]",
                           "theory [deg/h]", "ratio", "analog [deg/h]");
  for (const auto& row : r.white) {
    std::cout << fmt::format("{:>12.1f} {:>14.6f} {:>15.6f} {:>8.4f} {:>15.6f}\n", row.cutoff_hz,
                             row.rms, row.theory, ratio(row.rms, row.theory), row.theory_analog);
  }

  std::cout << "\nAngle random walk (raw white noise integrated; spread across runs)\n"
               "theory = sigma * dt * sqrt(t / dt), sigma in deg/s\n";
  std::cout << fmt::format("{:>12} {:>14} {:>15} {:>8}\n", "t [s]", "sigma [deg]", "theory [deg]",
                           "ratio");
  for (const auto& row : r.random_walk) {
    std::cout << fmt::format("{:>12.1f} {:>14.4e} {:>15.4e} {:>8.4f}\n", row.t_s, row.sigma,
                             row.theory, ratio(row.sigma, row.theory));
  }

  const double q = r.gauss_markov.empty() ? 0.0 : r.gauss_markov.front().q;
  std::cout << fmt::format(
      "\nFirst-order Gauss-Markov driven by the raw white noise, q = sigma^2 / dt = {:.4g} "
      "(deg/h)^2/s\ntheory = sqrt(q * tau / 2); within-run = mean of each run's own sigma\n",
      q);
  std::cout << fmt::format("{:>12} {:>14} {:>15} {:>8} {:>19}\n", "tau [s]", "sigma [deg/h]",
                           "theory [deg/h]", "ratio", "within-run [deg/h]");
  for (const auto& row : r.gauss_markov) {
    std::cout << fmt::format("{:>12.1f} {:>14.4f} {:>15.4f} {:>8.4f} {:>19.4f}\n", row.tau_s,
                             row.sigma, row.theory, ratio(row.sigma, row.theory),
                             row.within_run_sigma);
  }
}

}  // namespace

void register_noise_study(CLI::App& app) {
  auto args = std::make_shared<NoiseStudyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "noise-study",
      "Simulate white, band-limited, random-walk and Gauss-Markov noise (seed notes exercise 2) "
      "and compare with theory. Rates in deg/h, angles in deg.");
  cmd->add_option("--runs", args->runs,
                  "Monte-Carlo runs, >= 2 (the method needs >= 100); runs * duration <= 1e6 s")
      ->type_name("N")
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "station seed (non-negative integer)")
      ->type_name("S")
      ->capture_default_str();
  cmd->add_option("--duration", args->duration,
                  "length of each run [s]; walk times beyond it are dropped")
      ->type_name("S")
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "print the result as JSON");
  cmd->callback([args] {
    const sim::NoiseStudyOptions options = to_options(*args);
    if (options.runs < 100) {
      // Still run: a quick look is useful, but the random-walk sigmas are then rough.
      std::cerr << fmt::format(
          "calstand: warning: --runs {}: the exercise's method needs at least 100 runs; the "
          "random-walk and long-tau Gauss-Markov sigmas of fewer runs scatter widely\n",
          options.runs);
    }
    sim::NoiseStudyResult result;
    try {
      result = sim::run_noise_study(options);
    } catch (const std::invalid_argument& e) {
      // Everything the user sets is checked above; this is a default the library rejects.
      throw core::InputError("noise-study", e.what());
    }
    if (args->json) {
      print_json(result);
    } else {
      print_tables(options, result);
    }
  });
}

}  // namespace calstand::cli

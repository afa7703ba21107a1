#include "progress_bar.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>

namespace calstand::cli {

std::string format_duration(double seconds) {
  const auto s = static_cast<long long>(std::llround(std::max(0.0, seconds)));
  return fmt::format("{}:{:02}:{:02}", s / 3600, (s / 60) % 60, s % 60);
}

ProgressBar::ProgressBar() : enabled_(isatty(STDERR_FILENO) != 0) {}

void ProgressBar::update(const daemon::Progress& p) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  drawn_ = true;
  constexpr int kWidth = 24;
  const double fraction =
      p.steps ? static_cast<double>(p.step) / static_cast<double>(p.steps) : 0.0;
  const int filled = static_cast<int>(fraction * kWidth);
  std::string label = p.label.size() > 32 ? p.label.substr(0, 31) + "~" : p.label;
  fmt::print(stderr, "\r[{}{}] step {}/{} {:<11} {:<32} ETA {}\x1b[K", std::string(filled, '#'),
             std::string(kWidth - filled, '.'), p.step + 1, p.steps, p.phase, label,
             format_duration(p.eta_s));
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (enabled_ && drawn_) fmt::print(stderr, "\n");
}

}  // namespace calstand::cli

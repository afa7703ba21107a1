#include "solver/noise_rows.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace calstand::solver {
namespace {

double median_duration_s(const std::vector<StepSummary>& steps) {
  std::vector<double> d;
  for (const StepSummary& s : steps) d.push_back(s.duration_s);
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d.empty() ? 0.0 : d[d.size() / 2];
}

}  // namespace

CaptureSegments segment_long_captures(const RunData& data, const std::vector<StepSummary>& steps) {
  CaptureSegments out;
  if (steps.size() != data.steps.size() || steps.empty()) return out;
  const double typical_s = std::max(median_duration_s(steps), 1.0);
  const double long_s = std::max(kLongCaptureS, kLongCaptureSteps * typical_s);
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const StepSummary& s = steps[k];
    if (!s.is_static || s.duration_s < long_s) continue;
    const auto& samples = data.steps[k].samples;
    const double segment_s =
        std::max(typical_s, s.duration_s / static_cast<double>(kMaxSegmentsPerCapture));
    const auto count = static_cast<std::size_t>(std::floor(s.duration_s / segment_s));
    if (count < 2) continue;
    if (out.segments.steps.empty()) {
      // The run's first sample, wherever it is: summaries count time from it.
      const store::StepData* first = &data.steps.front();
      for (const store::StepData& step : data.steps) {
        if (step.samples.front().receive_time_s < first->samples.front().receive_time_s) {
          first = &step;
        }
      }
      store::StepData start;
      start.step = first->step;
      start.samples.push_back(first->samples.front());
      start.table.push_back(first->table.front());
      out.segments.setup = data.setup;
      out.segments.steps.push_back(std::move(start));
    }
    // Equal numbers of samples per segment, the remainder spread over them.
    const std::size_t n = samples.size();
    for (std::size_t j = 0; j < count; ++j) {
      const std::size_t begin = j * n / count, end = (j + 1) * n / count;
      store::StepData seg;
      seg.step = data.steps[k].step;
      seg.step.label = fmt::format("{} (segment {} of {})", data.steps[k].step.label, j + 1, count);
      seg.samples.assign(samples.begin() + static_cast<std::ptrdiff_t>(begin),
                         samples.begin() + static_cast<std::ptrdiff_t>(end));
      seg.table.assign(data.steps[k].table.begin() + static_cast<std::ptrdiff_t>(begin),
                       data.steps[k].table.begin() + static_cast<std::ptrdiff_t>(end));
      out.segments.steps.push_back(std::move(seg));
      out.from_step.push_back(k);
    }
  }
  return out;
}

std::vector<StepSummary> noise_rows(const std::vector<StepSummary>& steps,
                                    const CaptureSegments& segments,
                                    const std::vector<StepSummary>& segment_rows,
                                    std::vector<NoiseRowSource>* sources) {
  std::vector<bool> split(steps.size(), false);
  for (std::size_t k : segments.from_step) split[k] = true;
  std::vector<std::pair<const StepSummary*, NoiseRowSource>> rows;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    if (!split[k]) rows.push_back({&steps[k], {false, k}});
  }
  // segment_rows[0] is the run's first sample alone.
  if (!segments.empty()) {
    for (std::size_t j = 1; j < segment_rows.size(); ++j)
      rows.push_back({&segment_rows[j], {true, j}});
  }
  std::stable_sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
    return a.first->start_s < b.first->start_s;
  });
  std::vector<StepSummary> out;
  out.reserve(rows.size());
  if (sources) sources->clear();
  for (const auto& [row, source] : rows) {
    out.push_back(*row);
    if (sources) sources->push_back(source);
  }
  return out;
}

std::vector<StepSummary> summarize_noise_rows(const RunData& data, const Model& model,
                                              const std::vector<StepSummary>& steps) {
  const CaptureSegments segments = segment_long_captures(data, steps);
  if (segments.empty()) return steps;
  return noise_rows(steps, segments, summarize_steps(segments.segments, model));
}

}  // namespace calstand::solver

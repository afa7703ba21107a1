// The noise rows (solver/noise_rows.hpp): a long static capture enters by its segments' means,
// everything else by its step mean, in time order, with elapsed time counted from the run's
// first sample as in the whole run's summaries.
#include "solver/noise_rows.hpp"

#include <gtest/gtest.h>

#include "sim_run.hpp"

namespace calstand::solver {
namespace {

using testing::SimStep;

RunData run_with_capture(double capture_s) {
  std::vector<SimStep> steps = testing::six_positions(25.0, 30.0);
  SimStep capture;
  capture.duration_s = capture_s;
  capture.gap_before_s = 10.0;
  steps.insert(steps.begin() + 2, capture);
  return testing::simulate_run(testing::white_noise_truth(2e-3, 5e-4, 50.0), steps, 3);
}

TEST(NoiseRows, ALongStaticCaptureEntersByItsSegmentsInTimeOrder) {
  const RunData data = run_with_capture(1200.0);
  const Model model = Model::parse("gyro_bias,accel_bias,earth_rate");
  const std::vector<StepSummary> steps = summarize_steps(data, model);
  const CaptureSegments segments = segment_long_captures(data, steps);
  // 1200 s in segments of a typical step's length (30 s): 40 segments, the most allowed.
  ASSERT_EQ(segments.from_step.size(), kMaxSegmentsPerCapture);
  for (std::size_t k : segments.from_step) EXPECT_EQ(k, 2u);
  std::vector<NoiseRowSource> sources;
  const std::vector<StepSummary> rows =
      noise_rows(steps, segments, summarize_steps(segments.segments, model), &sources);
  ASSERT_EQ(rows.size(), steps.size() - 1 + kMaxSegmentsPerCapture);
  std::int64_t segment_samples = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (i > 0) {
      EXPECT_GE(rows[i].start_s, rows[i - 1].end_s);
    }
    if (sources[i].segment) segment_samples += rows[i].count;
  }
  // Every sample of the capture is in one segment, and the segments are the capture's time.
  EXPECT_EQ(segment_samples, steps[2].count);
  EXPECT_NEAR(rows[2].start_s, steps[2].start_s, 1e-9);
  EXPECT_NEAR(rows[2 + kMaxSegmentsPerCapture - 1].end_s, steps[2].end_s, 1e-9);
  // A segment's mean is the mean of its samples, as the whole capture's is of all of them.
  double weighted = 0.0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (sources[i].segment) weighted += rows[i].measured[kGz] * static_cast<double>(rows[i].count);
  }
  EXPECT_NEAR(weighted / static_cast<double>(steps[2].count), steps[2].measured[kGz], 1e-12);
}

TEST(NoiseRows, StepsOfATypicalLengthAreLeftWhole) {
  const RunData data = run_with_capture(90.0);
  const Model model = Model::parse("gyro_bias,accel_bias,earth_rate");
  const std::vector<StepSummary> steps = summarize_steps(data, model);
  EXPECT_TRUE(segment_long_captures(data, steps).empty());
  EXPECT_EQ(summarize_noise_rows(data, model, steps).size(), steps.size());
}

}  // namespace
}  // namespace calstand::solver

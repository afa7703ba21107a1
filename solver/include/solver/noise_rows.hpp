#pragma once
// The rows a run's noise model is estimated from: every step's mean, except that a long static
// capture enters as the means of its consecutive segments.
//
// Why. A step mean says nothing of how the bias moved inside the step. A static capture of half
// an hour or more (a stability capture, a warm-up record) holds, at the time scales it covers,
// exactly what the wander is: its Allan curve measures the Gauss-Markov, flicker and random
// walk that the step means then carry. Its segments' means put that evidence into the same
// likelihood as the step means (the exact likelihood of the segment means, rather than an
// approximation from Allan points), so that a wander estimated from the run must also be one
// the capture shows, and a transient inside the capture (a warm-up in plain sight) must be
// explained by the wander at every time scale at once or not at all.

#include <cstddef>
#include <vector>

#include "solver/model.hpp"
#include "solver/step_summary.hpp"

namespace calstand::solver {

/// A static step of at least this length [s], and of at least kLongCaptureSteps typical steps,
/// is split into segments.
inline constexpr double kLongCaptureS = 300.0;
inline constexpr double kLongCaptureSteps = 4.0;
/// A capture is split into segments of a typical step's length, and into at most this many.
inline constexpr std::size_t kMaxSegmentsPerCapture = 40;

/// The long static captures of a run, cut into segments (each a store::StepData holding a copy
/// of its samples: the captures only, not the whole run).
struct CaptureSegments {
  /// A run whose first step is the run's first sample alone (so that elapsed time and the
  /// segments' times are the run's), then the segments in time order; empty when the run has
  /// no long static capture.
  RunData segments;
  /// Per segment (after the first sample's step): the index into the run's steps it came from.
  std::vector<std::size_t> from_step;
  bool empty() const { return from_step.empty(); }
};

/// The long static captures of `data` (judged on `steps`, its summaries in step order) cut into
/// segments.
CaptureSegments segment_long_captures(const RunData& data, const std::vector<StepSummary>& steps);

/// Where a noise row comes from: a whole step (its position in the run's steps) or a segment
/// (its position in CaptureSegments::segments.steps, 1 or more).
struct NoiseRowSource {
  bool segment = false;
  std::size_t index = 0;
};

/// The noise rows: `steps` (summaries of `data`'s steps in order) with each long capture's row
/// replaced by `segment_rows` (summaries of `segments.segments` for the same model, the first
/// sample's step included), in time order; where each came from in `sources` when given.
std::vector<StepSummary> noise_rows(const std::vector<StepSummary>& steps,
                                    const CaptureSegments& segments,
                                    const std::vector<StepSummary>& segment_rows,
                                    std::vector<NoiseRowSource>* sources = nullptr);

/// The same in one call: the summaries of the segments for `model` and the rows.
std::vector<StepSummary> summarize_noise_rows(const RunData& data, const Model& model,
                                              const std::vector<StepSummary>& steps);

}  // namespace calstand::solver

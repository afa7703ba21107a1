#pragma once
// The wander of a unit measured on a static run, for the fit and diagnosis of another run of the
// same unit (`calstand fit|diagnose --noise-run ID`).
//
// Why: a run's own step means are all it has to tell a wandering bias from an effect that moves
// slowly with time (a warm-up after power-on), and both explain the same residual. Where the
// wander is re-estimated under each explanation (solver/effect_or_wander.hpp), it takes its
// share of the warm-up, and its own estimate is uncertain: a warm-up of 5 step means' noise on a
// MEMS-class gyro is then below what one thermal campaign can tell without false alarms
// (docs/guide-loop.md). A static run of the same unit (hours at rest, on another day, after it
// has warmed up) holds the wander and nothing else.
//
// How: the static record is cut into segments of the run's typical step length, and the wander
// is estimated from their means exactly as a run's own is (solver/noise_estimate.hpp: the same
// processes, restricted likelihood, BIC), with nothing but a bias to compete. Not from the
// record's composite noise model (noise/composite_noise.hpp): its selection answers the whole
// spectrum, and on 2 h of an LN200-class gyro it kept white noise alone while the Gauss-Markov
// bias (0.35 deg/h, 100 s) still moves a 20 s step mean by a third of its white scatter; the
// step means' own likelihood weighs what the step means carry.

#include <cstdint>
#include <string>

#include "solver/step_noise.hpp"
#include "solver/step_summary.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// The segments of `record`'s first step (a capture at rest), each `segment_s` long, as the
/// steps of a run (the setup kept): the step means whose wander is estimated.
solver::RunData segment_record(const solver::RunData& record, double segment_s);

/// A stored static record is read as at most this many samples (block means beyond): memory
/// stays about 100 MB whatever the record's length.
inline constexpr std::int64_t kMaxStaticSamples = std::int64_t{1} << 20;
/// Fewer segment means than this and a static record cannot tell its wander.
inline constexpr std::size_t kMinStaticSegments = 20;
/// A long record is cut into at most this many segments (longer ones then): the wander's
/// likelihood costs the square of their count, and 400 means of a 3 h record at 27 s already
/// reach every time scale a campaign's steps share.
inline constexpr std::size_t kMaxStaticSegments = 400;

/// Each channel's wander from `record` (a run whose first step is a capture at rest of the
/// unit), estimated from the means of segments of `run`'s typical step length (its median step
/// duration), for `run`. Throws core::InputError naming `source` when the record gives fewer
/// than kMinStaticSegments segments.
solver::KnownWander wander_of_static_record(const solver::RunData& record,
                                            const solver::RunData& run, const std::string& source);

/// The wander of `device` ("" = the run's only IMU) measured on the static run `noise_run`
/// (its longest capture at rest, solver::choose_noise_step()), for `run` (the run it will
/// weigh). Throws core::InputError for an unknown run or device, a run without a capture at
/// rest, a record too short, or a unit whose serial is not `run`'s.
solver::KnownWander noise_run_wander(store::Database& db, std::int64_t noise_run,
                                     const std::string& device, const solver::RunData& run);

/// Throws core::InputError naming --noise-run: `run` was recorded without a table, and its
/// poses are weighed by their own noise, not a static run's.
[[noreturn]] void throw_noise_run_on_table_free(std::int64_t run);

}  // namespace calstand::analysis

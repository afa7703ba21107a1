#pragma once
// The plots of the report's datasheet figures (the bandwidth's gain curve is bandwidth_svg()),
// each one gnuplot script rendered to inline SVG. Every function throws core::InputError naming
// gnuplot when it is missing or fails.

#include <string>

#include "datasheet/hysteresis.hpp"
#include "datasheet/repeatability.hpp"
#include "datasheet/warmup.hpp"
#include "report/report_data.hpp"

namespace calstand::analysis {

/// The turn-on bias of each power cycle less the mean over the cycles, per axis: gyros [deg/h]
/// above, accelerometers [ug] below.
std::string repeatability_plot(const RepeatabilityAnalysis& r);

/// The warm-up capture's bin means less each channel's settled value against time from
/// power-up, with the fit (WarmupSeries::fitted) where a transient is resolved: gyros [deg/h]
/// above, accelerometers [ug] below.
std::string warmup_plot(const WarmupAnalysis& w, const WarmupSeries& series);

/// Each bias fitted on the way up less on the way down, with its 1-sigma bar, against the set
/// point: gyros [deg/h] above, accelerometers [ug] below.
std::string hysteresis_plot(const HysteresisAnalysis& h);

}  // namespace calstand::analysis

#pragma once
// Printing the calibration of a run without a table (analysis/table_free_fit.hpp), and the
// options that steer its static-pose detection, shared by `calstand fit` and `calstand show`.

#include <CLI/CLI.hpp>
#include <string>

#include "analysis/table_free_diagnose.hpp"
#include "analysis/table_free_fit.hpp"

namespace calstand::cli {

/// What the command line says about the static poses of a run without a table.
struct StaticPoseOptions {
  std::string intervals_file;  ///< CSV of start_s,end_s per line: the poses, not detected
  analysis::TableFreeFitRequest request;
};

/// Adds --static-intervals, --static-window, --static-min, --rest, --threshold-multiple and
/// --false-alarm to `cmd`.
void add_static_pose_options(CLI::App* cmd, StaticPoseOptions& opt);

/// The request with the intervals file read (core::InputError naming the file and line).
analysis::TableFreeFitRequest static_pose_request(const StaticPoseOptions& opt,
                                                  const std::string& device);

/// The detector's choices and every static interval, one line each.
void print_static_poses(const analysis::TableFreePoses& poses);

/// The method, the parameters with sigma and status, what the poses do not determine, and the
/// fit quality in words.
void print_table_free_fit(const analysis::TableFreeFit& fit);

/// One line: chi2/dof, parameters, |f| - g and the gravity direction after the turns.
void print_table_free_quality(const analysis::TableFreeFit& fit);

/// The model's quality, where it fails most, the candidate terms ranked and the advice.
void print_table_free_diagnosis(const analysis::TableFreeDiagnosis& diagnosis);

}  // namespace calstand::cli

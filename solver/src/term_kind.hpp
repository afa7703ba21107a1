#pragma once
// What each catalogue term contributes to the regressors, for the two places that build them:
// Model::regressors() per sample and StepRegressorSums per step.

#include "core/error_terms.hpp"

namespace calstand::solver::detail {

enum class TermKind : unsigned char {
  kBias,
  kScale,
  kMisalignment,
  kAsymmetry,
  kGyroQuadratic,
  kAccelQuadratic,
  kGSensitivity,
  kTempBias,
  kTempScale,
  kLeverArm,
  kTilt,
  kNoParameters
};

/// The kind of a catalogue term, by its place in the catalogue: the regressors are built for
/// every term at every sample, where comparing the names took a tenth of a fit's time.
TermKind term_kind(const core::ErrorTermInfo* info);

}  // namespace calstand::solver::detail

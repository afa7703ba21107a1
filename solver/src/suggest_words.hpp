#pragma once
// The words of a suggested custom term: its name, its time constant as written, and what it says
// the effect is (suggest.cpp).

#include <set>
#include <string>

#include "solver/custom_term.hpp"
#include "solver/fit.hpp"

namespace calstand::solver::detail {

/// A searched time constant as the term writes it: three significant digits.
std::string format_tau(double tau_s);

/// A term name from its expression: force_z^2 -> force_z_sq, exp(-elapsed/900) -> exp_elapsed_900.
std::string name_of(const std::string& expression, const std::set<std::string>& taken);

/// What the term `spec` fitted in `fit` says the effect is, with its coefficients per axis; a
/// warm-up transient when `tau_s` is positive.
std::string effect_words(const CustomTermSpec& spec, const FitResult& fit, double tau_s);

}  // namespace calstand::solver::detail

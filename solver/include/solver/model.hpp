#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/error_terms.hpp"
#include "solver/custom_term.hpp"
#include "solver/signals.hpp"

namespace calstand::solver {

/// Rows of a regressor block: the six measurement channels.
enum Channel : int { kGx = 0, kGy, kGz, kAx, kAy, kAz, kChannels };
std::string_view channel_name(int channel);  ///< "gx" .. "az"

/// One term of a model: a catalogue term (with its temperature order) or a custom term.
struct ModelTerm {
  const core::ErrorTermInfo* info = nullptr;  ///< null for a custom term
  int order = 1;                              ///< temp_bias polynomial order N
  int custom = -1;                            ///< index into Model::customs(), else -1
  std::string name;                           ///< "gyro_temp_bias:2", "grad", ...
};

/// One fitted parameter.
struct ParameterInfo {
  std::string name;  ///< full name, e.g. "gyro_misalignment.xz"
  std::string unit;  ///< the contract's unit
  std::string term;  ///< the term it belongs to ("gyro_temp_bias:2")
  core::TermSensor sensor = core::TermSensor::kGyro;
};

/// An error model: the term registry applied to a list of terms. It names the parameters and
/// gives, per sample, the reference measurement and d(measurement)/d(parameter) for each
/// parameter (the regressors), both exactly as error-model.md writes the contributions. The
/// terms are linear in their parameters, so step averages of the regressors give the step
/// averages of the model exactly.
///
/// Copies share the custom-term evaluators, which are not thread safe: use one Model per thread.
class Model {
 public:
  /// Parses `terms`, comma-separated catalogue names (`gyro_temp_bias:2` for order 2), and
  /// custom terms `NAME=SENSOR:EXPRESSION` (also listed in `terms` by NAME or not at all).
  /// Throws core::InputError naming the bad term, with a suggestion for a misspelt one.
  static Model parse(std::string_view terms, const std::vector<std::string>& customs = {});
  Model() = default;
  Model(std::vector<ModelTerm> terms, std::vector<CustomTermSpec> customs);

  const std::vector<ModelTerm>& terms() const { return terms_; }
  const std::vector<CustomTermSpec>& customs() const { return customs_; }
  const std::vector<ParameterInfo>& parameters() const { return parameters_; }
  std::size_t size() const { return parameters_.size(); }
  bool earth_rate() const { return earth_rate_; }
  /// The term named `name` (catalogue name without order, or custom name), or nullptr.
  const ModelTerm* find(std::string_view name) const;
  /// Comma-separated term list that parse() reads back (customs as NAME).
  std::string text() const;
  /// Parameter index range [first, first + count) of term `t`.
  std::pair<std::size_t, std::size_t> parameter_range(std::size_t t) const;

  /// A copy with one more term (catalogue term of `order`, or replacing the order of a
  /// temp_bias term already present) or one more custom term.
  Model with_term(const core::ErrorTermInfo& info, int order = 1) const;
  Model with_custom(const CustomTermSpec& spec) const;

  /// Reference measurement of the signals (rate and force as the model sees them; error-model
  /// "Measurement model" without sensor terms): gyro rows w, accel rows f.
  Eigen::Matrix<double, kChannels, 1> reference(const Signals& s) const;

  /// Fills `out` (kChannels x size(), overwritten) with d(measurement)/d(parameter).
  void regressors(const Signals& s, Eigen::Ref<Eigen::MatrixXd> out) const;

 private:
  void index_parameters();
  std::vector<ModelTerm> terms_;
  std::vector<CustomTermSpec> customs_;
  std::vector<ParameterInfo> parameters_;
  std::vector<std::size_t> first_parameter_;  // per term
  std::vector<std::shared_ptr<CustomTermEvaluator>> evaluators_;
  bool earth_rate_ = false;
};

}  // namespace calstand::solver

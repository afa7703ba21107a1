#pragma once
// The step means of a model's regressors in one pass over a step's samples, without building
// the kChannels x parameters regressor matrix of every sample (issue 28: for the noise
// superset, every catalogue term, that matrix took most of a long run's fit).
//
// Every regressor of the catalogue is a constant times one per-sample product of the signals
// (a rate, a force, their absolute values or squares, a power of dT, dT times a rate or force,
// a product of two table rates, a tilt column), and many parameters share one: the scale
// factors and misalignments take the same rates and forces, every axis of a temperature
// polynomial the same power of dT, the gyro g-sensitivity the forces. The mean of a constant
// times a product is the constant times the product's mean, so summing each product the model
// needs once per sample and scattering the means at the end gives the same step means (to
// rounding) for a fraction of the work. A custom term's expression is a product of its own,
// evaluated per sample (muParser) on the axes it acts on.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "solver/model.hpp"
#include "solver/signals.hpp"

namespace calstand::solver {

/// Sums of the signal products `model`'s regressors are made of, over the samples added since
/// construction or clear(). Holds its own evaluators of the model's custom terms: one per
/// thread, like Model.
class StepRegressorSums {
 public:
  explicit StepRegressorSums(const Model& model);
  ~StepRegressorSums();
  StepRegressorSums(const StepRegressorSums&) = delete;
  StepRegressorSums& operator=(const StepRegressorSums&) = delete;

  /// Forgets the samples added (the next step starts).
  void clear();
  /// Adds one sample's signals.
  void add(const Signals& s);
  /// The mean over `count` samples (the number added) of Model::regressors():
  /// kChannels x model.size(), overwritten.
  void mean(std::int64_t count, Eigen::Ref<Eigen::MatrixXd> out) const;

  /// Number of products summed per sample (against kChannels x parameters before).
  std::size_t product_count() const { return sums_.size(); }

 private:
  struct Layout;
  /// One regressor entry: out(row, column) += coefficient * mean of product `product`
  /// (a negative product: the coefficient itself, a constant regressor).
  struct Entry {
    int row = 0;
    Eigen::Index column = 0;
    int product = -1;
    double coefficient = 1.0;
  };
  std::unique_ptr<Layout> layout_;
  std::vector<Entry> entries_;
  std::vector<double> sums_;
};

}  // namespace calstand::solver

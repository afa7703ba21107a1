#include "solver/suggest.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/tools/minima.hpp>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <tuple>

#include "core/error.hpp"
#include "held_out.hpp"
#include "solver/custom_term.hpp"
#include "solver/groups.hpp"
#include "solver/noise_estimate.hpp"
#include "solver/signals.hpp"
#include "suggest_words.hpp"

namespace calstand::solver {
namespace {

using detail::effect_words;
using detail::Folds;
using detail::format_tau;
using detail::held_out_chi2;
using detail::make_folds;
using detail::name_of;

// "Very strong" evidence on the Kass-Raftery scale of BIC differences, as diagnose asks of a
// catalogue term before recommending it.
constexpr double kStrongDeltaBic = -10.0;
// Why a warm-up is not judged by its likelihood ratio against the wander at a lower bar than
// BIC's (for a triad 3 ln(rows) + ln(3 rows) + 10, about 32, where a 5-sigma warm-up of a MEMS
// gyro brings 20-45): chi-square with 3 degrees of freedom at 5e-5 (1e-3 after the time
// constant's search) would ask 22.6. Before the noise floor was the white part of the steps'
// Allan curve (octave_allan.hpp), the clean-run statistic (2 ln LR less the wanders' cost
// change, bench/warm_up_detection_bench.cpp `evidence 0`) had a heavy tail on ADIS16488-class
// accelerometers (up to 44, a floor 28 times their white noise); it is now at most 13 there and
// 27 on the gyros in 120 runs, but a sample of hundreds cannot show a 1e-3 rate, and BIC's
// "very strong" bar keeps 0 alarms in 200 ADIS16488- and MEMS-class clean runs.
// The warm-up form stated before the search is a decay that settles within the run: a time
// constant of at most this fraction of the run's span (5 % of it left at the end). A slower
// decay is a drift across the run, which a flicker or a random walk bias makes as readily (an
// ADIS16488-class clean run with a 30 min capture gave accel exp(-elapsed/8530) at BIC -11.3
// against the wander, 2 ln LR 44, in a 4 h run, bench/warm_up_detection_bench.cpp `evidence 0`
// seed 96419): it is judged as every searched form is, with the look-elsewhere cost.
constexpr double kWarmUpSettlesWithinRun = 1.0 / 3.0;
// "Strong" evidence on the same scale: the warm-up's bar when the wander is known (measured on a
// static run of the unit, analysis/noise_run.hpp), not re-estimated from the run. The very
// strong bar above answers the tail of a statistic whose null holds a wander fitted to the same
// step means; with the wander given, the comparison is a likelihood ratio under a known noise.
// With the wander a 3 h static run measured (bench/warm_up_detection_bench.cpp `known 0`), 80
// MEMS-class and 80 ADIS16488-class clean runs reach 2 ln LR 21.5 and 14.4 at most, BIC against
// the wander -0.5 and +0.8 at least: -6 keeps a margin of 5.5 and none alarms, where -10 found
// fewer 5x ADIS16488-class warm-ups with the static run's wander than with the run's own.
constexpr double kStrongDeltaBicKnownWander = -6.0;
// A form whose whitened column lies within this sine of the catalogue's span on a channel (all
// but 1e-4 of its variance there) is that catalogue effect, which the user should add by name.
constexpr double kCatalogueSine = 1e-2;
// Transient time constants per decade on the grid: the chi-square is smooth in log tau at this
// resolution (a factor 1.5), and Brent's method refines the best point.
constexpr double kTausPerDecade = 6.0;
// Bits of log10(tau) Brent's method resolves: 2^-19 (a factor 1 + 1e-6 in tau) is far below
// the three significant digits the term writes.
constexpr int kTauBrentBits = 20;

// --- Building blocks: the step means of every signal, product of two, and absolute value -----

constexpr std::size_t kS = kSignalCount;
constexpr std::size_t kProducts = kS * (kS + 1) / 2;  // squares included
constexpr std::size_t kBlocks = kS + kProducts + kS;
// First signal index of the per-axis signals (rate_x, force_x, table_rate_x); the three scalar
// signals (temperature, temperature_rate, elapsed) come before them.
constexpr std::array<std::size_t, 3> kAxisFamilies{3, 6, 9};
constexpr std::size_t kScalars = 3;
constexpr int kTransient = -1;  // block index of the exp(-elapsed/tau) column

std::size_t linear_block(std::size_t k) { return k; }
std::size_t product_block(std::size_t j, std::size_t k) {
  if (j > k) std::swap(j, k);
  return kS + j * (2 * kS - j + 1) / 2 + (k - j);  // rows j' < j hold kS - j' products each
}
std::size_t abs_block(std::size_t k) { return kS + kProducts + k; }
bool is_product(std::size_t b) { return b >= kS && b < kS + kProducts; }
/// The signals (j <= k) of product block `b`.
std::pair<std::size_t, std::size_t> product_signals(std::size_t b) {
  std::size_t j = 0;
  while (product_block(j, kS - 1) < b) ++j;
  return {j, j + (b - product_block(j, j))};
}

std::string signal_text(std::size_t k) { return std::string(signal_names()[k]); }
/// "force_{axis}" for the family whose x signal is `first`.
std::string family_text(std::size_t first) {
  const std::string x = signal_text(first);
  return x.substr(0, x.size() - 1) + "{axis}";
}

std::string block_text(std::size_t b) {
  if (b < kS) return signal_text(b);
  if (!is_product(b)) return "abs(" + signal_text(b - kS - kProducts) + ")";
  const auto [j, k] = product_signals(b);
  return j == k ? signal_text(j) + "^2" : signal_text(j) + "*" + signal_text(k);
}

/// Step means (rows: steps of `data` in order) of every building block, in one pass over the
/// samples with the signals exactly as the model's custom terms see them.
Eigen::MatrixXd block_means(const RunData& data, bool earth_rate) {
  const SignalBuilder build(data.setup, earth_rate);
  const double run_start_s = data.steps.front().samples.front().receive_time_s;
  Eigen::MatrixXd out(static_cast<Eigen::Index>(data.steps.size()),
                      static_cast<Eigen::Index>(kBlocks));
  for (std::size_t i = 0; i < data.steps.size(); ++i) {
    const store::StepData& step = data.steps[i];
    const std::vector<double> rates = step_temperature_rates(step.samples);
    std::array<double, kBlocks> sum{};
    for (std::size_t n = 0; n < step.samples.size(); ++n) {
      const core::ImuSample& sample = step.samples[n];
      const auto v = signal_values(
          build(sample, step.table[n], rates[n], sample.receive_time_s - run_start_s));
      std::size_t p = kS;
      for (std::size_t j = 0; j < kS; ++j) {
        sum[j] += v[j];
        sum[kS + kProducts + j] += std::abs(v[j]);
        for (std::size_t k = j; k < kS; ++k) sum[p++] += v[j] * v[k];
      }
    }
    const double inv_n = 1.0 / static_cast<double>(step.samples.size());
    for (std::size_t b = 0; b < kBlocks; ++b) {
      out(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(b)) = sum[b] * inv_n;
    }
  }
  return out;
}

bool is_rate(std::size_t i) { return i >= kAxisFamilies[0] && i < kAxisFamilies[1]; }

// A block whose step means all stay below this share of its signals' size is zero but for
// rounding (force_x*force_y when the table only ever tips the IMU about body axes): a fit would
// scale the rounding up by 1e12 to match whatever it happens to correlate with.
constexpr double kRoundingShare = 1e-9;

/// Per block: true when it adds nothing: its step means are zero but for rounding, it follows
/// the Earth rate alone, or it is the abs() of a signal that never changes sign (elapsed), i.e.
/// the signal itself.
std::vector<bool> useless_blocks(const Eigen::MatrixXd& blocks) {
  std::array<double, kS> size{};
  for (std::size_t k = 0; k < kS; ++k) {
    size[k] = std::sqrt(blocks.col(static_cast<Eigen::Index>(product_block(k, k))).maxCoeff());
  }
  std::vector<bool> out(kBlocks, false);
  for (std::size_t b = 0; b < kBlocks; ++b) {
    double scale = 0.0;
    if (b < kS) {
      scale = size[b];
    } else if (is_product(b)) {
      const auto [j, k] = product_signals(b);
      scale = size[j] * size[k];
    } else {
      scale = size[b - kS - kProducts];
    }
    out[b] =
        !(blocks.col(static_cast<Eigen::Index>(b)).cwiseAbs().maxCoeff() > kRoundingShare * scale);
  }
  // A rate block whose table-rate twin vanishes varies only with the Earth rate (a static run):
  // its coefficient would be absurd, though its column may equal a physical one (rate_z^2
  // follows force_z^2 when the table tips about North).
  const auto table_twin = [](std::size_t i) {
    return is_rate(i) ? i + kAxisFamilies[2] - kAxisFamilies[0] : i;
  };
  for (std::size_t j = 0; j < kS; ++j) {
    if (is_rate(j) && out[linear_block(table_twin(j))]) {
      out[linear_block(j)] = out[abs_block(j)] = true;
    }
    for (std::size_t k = j; k < kS; ++k) {
      if ((is_rate(j) || is_rate(k)) && out[product_block(table_twin(j), table_twin(k))]) {
        out[product_block(j, k)] = true;
      }
    }
  }
  for (std::size_t k = 0; k < kS; ++k) {
    const auto a = blocks.col(static_cast<Eigen::Index>(abs_block(k)));
    const auto v = blocks.col(static_cast<Eigen::Index>(linear_block(k)));
    const double tolerance = kRoundingShare * size[k];
    if ((a - v).cwiseAbs().maxCoeff() <= tolerance || (a + v).cwiseAbs().maxCoeff() <= tolerance) {
      out[abs_block(k)] = true;
    }
  }
  return out;
}

/// Step means of exp(-elapsed/tau) over each step's samples, evenly spaced from start_s to
/// end_s (a geometric series: exact for a steady sample rate, without visiting the samples).
Eigen::VectorXd transient_column(const std::vector<StepSummary>& steps, double tau_s) {
  Eigen::VectorXd v(static_cast<Eigen::Index>(steps.size()));
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const StepSummary& s = steps[i];
    const double n = static_cast<double>(std::max<std::int64_t>(s.count, 1));
    const double h = n > 1.0 ? (s.end_s - s.start_s) / (n - 1.0) : 0.0;
    const double series = h > 0.0 ? std::expm1(-n * h / tau_s) / (n * std::expm1(-h / tau_s)) : 1.0;
    v[static_cast<Eigen::Index>(i)] = std::exp(-s.start_s / tau_s) * series;
  }
  return v;
}

// --- The model's whitened problem and the screening of one column ---------------------------

/// The model's fit as the screening sees it, per fitted channel: the whitening (Cholesky factor
/// of the step means' covariance under the diagnosis's noise model), that channel's rows of an
/// orthonormal basis of the model's whitened columns (all channels stacked, so that parameters
/// acting on several channels couple them), the whitened residual, and an orthonormal basis of
/// the catalogue's whitened columns on the channel.
struct Whitened {
  Eigen::Index steps = 0;
  std::array<int, kChannels> position{-1, -1, -1, -1, -1, -1};
  std::vector<Eigen::MatrixXd> lower;  ///< Cholesky factor per fitted channel
  std::vector<Eigen::MatrixXd> basis;  ///< S x k block of the stacked basis
  std::vector<Eigen::VectorXd> residual;
  std::vector<Eigen::MatrixXd> catalogue;
  double log_rows = 0.0;
  double near_collinear_sine = 1e-3;
};

Whitened whiten(const SuggestInput& in, const FitResult& fit, const FitOptions& options) {
  const std::vector<StepSummary>& steps = *in.steps;
  Whitened w;
  w.steps = static_cast<Eigen::Index>(steps.size());
  w.near_collinear_sine = options.near_collinear_sine;
  w.log_rows = std::log(static_cast<double>(fit.dof + static_cast<int>(fit.parameters.size())));
  std::vector<Eigen::Index> columns;
  for (const FittedParameter& p : fit.parameters) {
    const auto& all = in.model->parameters();
    const auto it = std::find_if(all.begin(), all.end(),
                                 [&](const ParameterInfo& q) { return q.name == p.name; });
    if (it != all.end()) columns.push_back(it - all.begin());
  }
  // The catalogue's span is that of the parameters the run determines: a term it barely excites
  // (gyro_quadratic on a static run, where the rate is the Earth's) explains nothing, though its
  // column may equal a custom one (rate_z^2 there follows force_z^2).
  std::set<std::string> determined;
  bool catalogue_fitted = true;
  try {
    for (const FittedParameter& p :
         fit_model(*in.catalogue_steps, *in.catalogue, fit.noise, options).parameters) {
      determined.insert(p.name);
    }
  } catch (const core::InputError&) {
    catalogue_fitted = false;  // more catalogue parameters than rows: take every column
  }
  const std::vector<int> channels = fit_channels(options.rows);
  const Eigen::Index S = w.steps;
  Eigen::MatrixXd A(S * static_cast<Eigen::Index>(channels.size()),
                    static_cast<Eigen::Index>(columns.size()));
  for (std::size_t ci = 0; ci < channels.size(); ++ci) {
    const int c = channels[ci];
    w.position[static_cast<std::size_t>(c)] = static_cast<int>(ci);
    const Eigen::LLT<Eigen::MatrixXd> llt(fit.noise.covariance(c, steps));
    w.lower.push_back(Eigen::MatrixXd(llt.matrixL()));
    const auto L = w.lower.back().triangularView<Eigen::Lower>();
    Eigen::MatrixXd X(S, static_cast<Eigen::Index>(columns.size()));
    Eigen::VectorXd e(S);
    for (Eigen::Index i = 0; i < S; ++i) {
      const StepSummary& s = steps[static_cast<std::size_t>(i)];
      for (std::size_t k = 0; k < columns.size(); ++k) {
        X(i, static_cast<Eigen::Index>(k)) = s.regressors(c, columns[k]);
      }
      e[i] = fit.steps[static_cast<std::size_t>(i)].residual[c];
    }
    A.middleRows(static_cast<Eigen::Index>(ci) * S, S) = L.solve(X);
    w.residual.push_back(L.solve(e));
    // The catalogue's columns on this channel, normalised, reduced to an orthonormal basis of
    // their span (temperature orders beyond the plateaus make some of them dependent).
    const std::vector<StepSummary>& cs = *in.catalogue_steps;
    std::vector<Eigen::Index> acting;
    for (Eigen::Index p = 0; p < static_cast<Eigen::Index>(in.catalogue->size()); ++p) {
      const std::string& name = in.catalogue->parameters()[static_cast<std::size_t>(p)].name;
      if (catalogue_fitted && !determined.count(name)) continue;
      bool nonzero = false;
      for (const StepSummary& s : cs) nonzero = nonzero || s.regressors(c, p) != 0.0;
      if (nonzero) acting.push_back(p);
    }
    Eigen::MatrixXd Xc(S, static_cast<Eigen::Index>(acting.size()));
    for (Eigen::Index i = 0; i < S; ++i) {
      for (std::size_t k = 0; k < acting.size(); ++k) {
        Xc(i, static_cast<Eigen::Index>(k)) =
            cs[static_cast<std::size_t>(i)].regressors(c, acting[k]);
      }
    }
    Xc = L.solve(Xc);
    for (Eigen::Index k = 0; k < Xc.cols(); ++k) Xc.col(k) /= Xc.col(k).norm();
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Xc.rows(), Xc.cols());
    qr.setThreshold(1e-9);
    qr.compute(Xc);
    const Eigen::MatrixXd Q = qr.householderQ();
    w.catalogue.push_back(Q.leftCols(qr.rank()));
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(A.rows(), A.cols());
  for (std::size_t ci = 0; ci < channels.size(); ++ci) {
    w.basis.push_back(Q.middleRows(static_cast<Eigen::Index>(ci) * S, S));
  }
  return w;
}

/// One column (a form's step means on one channel) as the screening needs it.
struct ColumnStats {
  bool usable = false;      ///< not collinear with the model, not a catalogue effect
  double projection = 0.0;  ///< whitened residual . whitened column
  double perp = 0.0;        ///< squared norm of the column outside the model's span
  Eigen::VectorXd inside;   ///< its coordinates in the model's basis
};

ColumnStats column_stats(const Whitened& w, int ci, const Eigen::VectorXd& step_means) {
  ColumnStats st;
  const auto uci = static_cast<std::size_t>(ci);
  const Eigen::VectorXd col = w.lower[uci].triangularView<Eigen::Lower>().solve(step_means);
  const double norm2 = col.squaredNorm();
  if (!(norm2 > 0.0) || !std::isfinite(norm2)) return st;
  st.inside = w.basis[uci].transpose() * col;
  st.perp = norm2 - st.inside.squaredNorm();
  const double sine2 = w.near_collinear_sine * w.near_collinear_sine;
  if (st.perp <= sine2 * norm2) return st;  // the fit would call it undetermined
  const double outside_catalogue = norm2 - (w.catalogue[uci].transpose() * col).squaredNorm();
  if (outside_catalogue <= kCatalogueSine * kCatalogueSine * norm2) return st;
  st.projection = w.residual[uci].dot(col);
  st.usable = true;
  return st;
}

/// The axes a form should act on and the BIC change it would bring there.
struct Screen {
  std::array<bool, 3> axes{false, false, false};
  double delta_bic = std::numeric_limits<double>::infinity();
};

/// Chi-square removed by the columns of the axes in `mask` together (b' M^-1 b with M the Gram
/// matrix of their parts outside the model's span), for each subset; the best BIC.
Screen best_axes(const Whitened& w, const std::array<const ColumnStats*, 3>& cols) {
  Screen best;
  for (unsigned mask = 1; mask < 8; ++mask) {
    std::vector<int> axes;
    for (int a = 0; a < 3; ++a) {
      if (mask & (1u << a)) axes.push_back(a);
    }
    bool ok = true;
    for (int a : axes) {
      ok = ok && cols[static_cast<std::size_t>(a)] && cols[static_cast<std::size_t>(a)]->usable;
    }
    if (!ok) continue;
    const auto m = static_cast<Eigen::Index>(axes.size());
    Eigen::MatrixXd M(m, m);
    Eigen::VectorXd b(m);
    for (Eigen::Index i = 0; i < m; ++i) {
      const ColumnStats& ci = *cols[static_cast<std::size_t>(axes[static_cast<std::size_t>(i)])];
      b[i] = ci.projection;
      for (Eigen::Index j = 0; j < m; ++j) {
        const ColumnStats& cj = *cols[static_cast<std::size_t>(axes[static_cast<std::size_t>(j)])];
        M(i, j) = i == j ? ci.perp : -ci.inside.dot(cj.inside);
      }
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(M);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) continue;
    const double removed = b.dot(ldlt.solve(b));
    const double delta = -removed + static_cast<double>(m) * w.log_rows;
    if (std::isfinite(delta) && delta < best.delta_bic) {
      best.delta_bic = delta;
      for (int a = 0; a < 3; ++a) best.axes[static_cast<std::size_t>(a)] = (mask & (1u << a)) != 0;
    }
  }
  return best;
}

// --- Forms ---------------------------------------------------------------------------------

struct Form {
  core::TermSensor sensor = core::TermSensor::kGyro;
  std::string expression;  ///< muParser, `{axis}` for a per-axis form
  std::array<int, 3> block{kTransient, kTransient, kTransient};  ///< building block per axis
  double tau_s = 0.0;                                            ///< the transient's time constant
};

/// rate_* is table_rate_* plus the Earth rate, so their product is in effect the Earth rate
/// times a table rate: a regressor that follows no physics and fits whatever it happens to
/// correlate with (its coefficients come out absurd).
bool earth_rate_product(std::size_t j, std::size_t k) {
  const auto table_rate = [](std::size_t i) { return i >= kAxisFamilies[2]; };
  return (is_rate(j) && table_rate(k)) || (table_rate(j) && is_rate(k));
}

bool per_axis(const Form& f) { return f.expression.find("{axis}") != std::string::npos; }

std::vector<Form> forms_of(core::TermSensor sensor) {
  std::vector<Form> out;
  const auto fixed = [&](std::size_t b) {
    const int bi = static_cast<int>(b);
    out.push_back({sensor, block_text(b), {bi, bi, bi}, 0.0});
  };
  for (std::size_t k = 0; k < kS; ++k) fixed(linear_block(k));
  for (std::size_t j = 0; j < kS; ++j) {
    for (std::size_t k = j; k < kS; ++k) {
      if (!earth_rate_product(j, k)) fixed(product_block(j, k));
    }
  }
  for (std::size_t k = 0; k < kS; ++k) fixed(abs_block(k));
  const auto axis_form = [&](std::string text, const auto& block_of) {
    Form f{sensor, std::move(text), {}, 0.0};
    for (std::size_t a = 0; a < 3; ++a) f.block[a] = static_cast<int>(block_of(a));
    out.push_back(std::move(f));
  };
  for (std::size_t fi = 0; fi < kAxisFamilies.size(); ++fi) {
    const std::size_t F = kAxisFamilies[fi];
    const std::string name = family_text(F);
    axis_form(name, [&](std::size_t a) { return linear_block(F + a); });
    axis_form(name + "^2", [&](std::size_t a) { return product_block(F + a, F + a); });
    axis_form("abs(" + name + ")", [&](std::size_t a) { return abs_block(F + a); });
    for (std::size_t gi = fi + 1; gi < kAxisFamilies.size(); ++gi) {
      const std::size_t G = kAxisFamilies[gi];
      if (earth_rate_product(F, G)) continue;
      axis_form(name + "*" + family_text(G),
                [&](std::size_t a) { return product_block(F + a, G + a); });
    }
    for (std::size_t s = 0; s < kScalars; ++s) {
      axis_form(signal_text(s) + "*" + name,
                [&](std::size_t a) { return product_block(s, F + a); });
    }
  }
  return out;
}

/// A form on the axes chosen for it, with its screening figure.
struct Screened {
  Form form;
  std::array<bool, 3> axes{};
  double screen_delta_bic = 0.0;
  std::string expression;  ///< as written in the term: `{axis}` resolved when one axis remains
  std::string key;         ///< sensor, axes and building block per axis: equal keys, equal terms
};

/// "gyro", "accel.xz": the SENSOR[.AXES] part of a term's text.
std::string sensor_text(core::TermSensor sensor, const std::array<bool, 3>& axes) {
  CustomTermSpec spec;
  spec.name = "k";
  spec.sensor = sensor;
  spec.axes = axes;
  const std::string text = spec.text();  // k=SENSOR[.AXES]:
  return text.substr(2, text.size() - 3);
}

Screened make_screened(const Form& f, const Screen& s) {
  Screened out{f, s.axes, s.delta_bic, f.expression, ""};
  int count = 0, only = 0;
  for (int a = 0; a < 3; ++a) {
    if (s.axes[static_cast<std::size_t>(a)]) {
      ++count;
      only = a;
    }
  }
  if (count == 1 && per_axis(f)) {
    std::string e = f.expression;
    for (auto pos = e.find("{axis}"); pos != std::string::npos; pos = e.find("{axis}")) {
      e.replace(pos, 6, std::string(1, "xyz"[only]));
    }
    out.expression = e;
  }
  out.key = f.sensor == core::TermSensor::kGyro ? "g" : "a";
  for (int a = 0; a < 3; ++a) {
    if (!s.axes[static_cast<std::size_t>(a)]) continue;
    out.key += fmt::format(":{}{}", "xyz"[a], f.block[static_cast<std::size_t>(a)]);
  }
  if (f.tau_s > 0.0) out.key += ":tau" + format_tau(f.tau_s);
  return out;
}

/// The smallest `f(x)` over [lo, hi], x the decimal log of a time constant: a grid of
/// kTausPerDecade points per decade (the curve may have more than one dip: the grid finds the
/// deepest), then Brent's method (Boost.Math) between the best point's neighbours. Returns
/// {x, f(x)}; f(x) is infinite when no grid point is finite.
template <class F>
std::pair<double, double> tau_minimum(F f, double lo, double hi) {
  const int count = std::max(2, static_cast<int>(std::ceil(kTausPerDecade * (hi - lo))) + 1);
  const double step = (hi - lo) / (count - 1);
  double best_x = lo, best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < count; ++i) {
    const double v = f(lo + step * i);
    if (v < best) {
      best = v;
      best_x = lo + step * i;
    }
  }
  if (!std::isfinite(best)) return {best_x, best};
  const auto refined = boost::math::tools::brent_find_minima(
      f, std::max(lo, best_x - step), std::min(hi, best_x + step), kTauBrentBits);
  if (refined.second < best) return refined;
  return {best_x, best};
}

/// The transient form of `sensor` with the best time constant: a log grid from a step's length
/// to beyond the run, then Brent's method between the best point's neighbours (tau_minimum).
std::pair<Form, Screen> best_transient(const Whitened& w, const std::vector<StepSummary>& steps,
                                       core::TermSensor sensor) {
  std::vector<double> durations;
  double span = 0.0;
  for (const StepSummary& s : steps) {
    durations.push_back(std::max(s.duration_s, 1.0));
    span = std::max(span, s.end_s);
  }
  std::nth_element(durations.begin(),
                   durations.begin() + static_cast<std::ptrdiff_t>(durations.size() / 2),
                   durations.end());
  const double lo = std::log10(std::max(1.0, durations[durations.size() / 2]));
  const double hi = std::log10(std::max(10.0 * std::pow(10.0, lo), 3.0 * span));
  const int base = sensor == core::TermSensor::kGyro ? kGx : kAx;
  const auto evaluate = [&](double log_tau) {
    const Eigen::VectorXd column = transient_column(steps, std::pow(10.0, log_tau));
    std::array<ColumnStats, 3> stats;
    std::array<const ColumnStats*, 3> ptr{nullptr, nullptr, nullptr};
    for (int a = 0; a < 3; ++a) {
      const int ci = w.position[static_cast<std::size_t>(base + a)];
      if (ci < 0) continue;
      stats[static_cast<std::size_t>(a)] = column_stats(w, ci, column);
      ptr[static_cast<std::size_t>(a)] = &stats[static_cast<std::size_t>(a)];
    }
    return best_axes(w, ptr);
  };
  const double best_x = tau_minimum([&](double x) { return evaluate(x).delta_bic; }, lo, hi).first;
  const Screen best = evaluate(best_x);
  Form f;
  f.sensor = sensor;
  // The time constant as the term will write it, so that the term is the one screened.
  f.tau_s = std::stod(format_tau(std::pow(10.0, best_x)));
  f.expression = "exp(-elapsed/" + format_tau(f.tau_s) + ")";
  return {f, best};
}

// --- Exact refits and the held-out check -----------------------------------------------------

/// Step means of a form per axis (columns x, y, z).
Eigen::MatrixXd form_columns(const Form& f, const Eigen::MatrixXd& blocks,
                             const std::vector<StepSummary>& steps) {
  Eigen::MatrixXd V(static_cast<Eigen::Index>(steps.size()), 3);
  for (Eigen::Index a = 0; a < 3; ++a) {
    const int b = f.block[static_cast<std::size_t>(a)];
    V.col(a) = b == kTransient ? transient_column(steps, f.tau_s) : Eigen::VectorXd(blocks.col(b));
  }
  return V;
}

/// A form's columns on the noise rows of `in.evidence` (per axis: x, y, z), built from the
/// steps' block means for whole steps and the segments' for the rows of a long capture.
Eigen::MatrixXd evidence_form_columns(const Form& f, const Eigen::MatrixXd& blocks,
                                      const Eigen::MatrixXd& segment_blocks,
                                      const SuggestInput& in) {
  const std::vector<StepSummary>& rows = in.evidence->rows();
  const auto R = static_cast<Eigen::Index>(rows.size());
  Eigen::MatrixXd V(R, 3);
  for (Eigen::Index a = 0; a < 3; ++a) {
    const int b = f.block[static_cast<std::size_t>(a)];
    if (b == kTransient) {
      V.col(a) = transient_column(rows, f.tau_s);
      continue;
    }
    for (Eigen::Index i = 0; i < R; ++i) {
      const NoiseRowSource& src = (*in.evidence_sources)[static_cast<std::size_t>(i)];
      V(i, a) = src.segment ? segment_blocks(static_cast<Eigen::Index>(src.index), b)
                            : blocks(static_cast<Eigen::Index>(src.index), b);
    }
  }
  return V;
}

/// `steps` with the custom term's regressors appended (the order Model::with_custom gives).
std::vector<StepSummary> with_columns(const std::vector<StepSummary>& steps,
                                      core::TermSensor sensor, const std::array<bool, 3>& axes,
                                      const Eigen::MatrixXd& V) {
  const int base = sensor == core::TermSensor::kGyro ? kGx : kAx;
  std::vector<StepSummary> out = steps;
  for (std::size_t i = 0; i < out.size(); ++i) {
    Eigen::MatrixXd& R = out[i].regressors;
    Eigen::Index p = R.cols();
    const auto added = static_cast<Eigen::Index>(std::count(axes.begin(), axes.end(), true));
    R.conservativeResize(Eigen::NoChange, p + added);
    R.rightCols(added).setZero();
    for (int a = 0; a < 3; ++a) {
      if (axes[static_cast<std::size_t>(a)]) R(base + a, p++) = V(static_cast<Eigen::Index>(i), a);
    }
  }
  return out;
}

/// Every form screened against the whitening `w`, best first.
std::vector<Screened> screen_forms(const Whitened& w, const Eigen::MatrixXd& blocks,
                                   const std::vector<StepSummary>& steps,
                                   const std::vector<core::TermSensor>& sensors, int* forms_tried) {
  const std::vector<bool> useless = useless_blocks(blocks);
  std::vector<Screened> screened;
  for (core::TermSensor sensor : sensors) {
    const int base_row = sensor == core::TermSensor::kGyro ? kGx : kAx;
    // Column statistics of every building block on each of the sensor's channels, once.
    std::array<std::vector<ColumnStats>, 3> stats;
    for (int a = 0; a < 3; ++a) {
      const int ci = w.position[static_cast<std::size_t>(base_row + a)];
      if (ci < 0) continue;
      for (std::size_t b = 0; b < kBlocks; ++b) {
        stats[static_cast<std::size_t>(a)].push_back(
            useless[b] ? ColumnStats{}
                       : column_stats(w, ci, blocks.col(static_cast<Eigen::Index>(b))));
      }
    }
    for (const Form& f : forms_of(sensor)) {
      ++*forms_tried;
      std::array<const ColumnStats*, 3> cols{nullptr, nullptr, nullptr};
      for (std::size_t a = 0; a < 3; ++a) {
        if (!stats[a].empty()) cols[a] = &stats[a][static_cast<std::size_t>(f.block[a])];
      }
      const Screen s = best_axes(w, cols);
      if (std::isfinite(s.delta_bic)) screened.push_back(make_screened(f, s));
    }
    ++*forms_tried;
    const auto [transient, s] = best_transient(w, steps, sensor);
    // The time constant is a parameter too.
    if (std::isfinite(s.delta_bic)) {
      screened.push_back(make_screened(transient, Screen{s.axes, s.delta_bic + w.log_rows}));
    }
  }
  std::stable_sort(screened.begin(), screened.end(), [](const Screened& a, const Screened& b) {
    return a.screen_delta_bic < b.screen_delta_bic;
  });
  return screened;
}

/// The transient of `sensor` as the noise rows show it: a long static capture enters them by its
/// segments, so a warm-up inside it (which its one step mean cannot show) is seen here. Each
/// channel's rows are weighted by the white noise, the noise superset's columns projected out;
/// the time constant (one for the triad) maximises the chi-square the transient removes on the
/// axes where it earns its parameter.
std::optional<Screened> transient_on_noise_rows(const SuggestInput& in, core::TermSensor sensor,
                                                const FitOptions& options) {
  const std::vector<StepSummary>& rows = in.evidence->rows();
  const auto R = static_cast<Eigen::Index>(rows.size());
  const int first = sensor == core::TermSensor::kGyro ? kGx : kAx;
  const double log_rows = in.evidence->log_rows();
  struct Channel {
    Eigen::VectorXd root_w;
    Eigen::MatrixXd Q;
    Eigen::VectorXd residual;
  };
  std::array<std::optional<Channel>, 3> channels;
  for (int a = 0; a < 3; ++a) {
    const int c = first + a;
    const std::vector<int> fitted = fit_channels(options.rows);
    if (std::find(fitted.begin(), fitted.end(), c) == fitted.end()) continue;
    Channel ch;
    ch.root_w.resize(R);
    Eigen::VectorXd y(R);
    const Eigen::Index P = rows.front().regressors.cols();
    Eigen::MatrixXd X(R, P);
    for (Eigen::Index i = 0; i < R; ++i) {
      const StepSummary& s = rows[static_cast<std::size_t>(i)];
      ch.root_w[i] = std::sqrt(static_cast<double>(s.count) / in.fit->noise.white.density[c]);
      y[i] = ch.root_w[i] * (s.measured[c] - s.reference[c]);
      X.row(i) = ch.root_w[i] * s.regressors.row(c);
    }
    for (Eigen::Index k = 0; k < P; ++k) {
      const double norm = X.col(k).norm();
      if (norm > 0.0) X.col(k) /= norm;
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X.rows(), X.cols());
    qr.setThreshold(1e-9);
    qr.compute(X);
    ch.Q = Eigen::MatrixXd(qr.householderQ()).leftCols(qr.rank());
    ch.residual = y - ch.Q * (ch.Q.transpose() * y);
    channels[static_cast<std::size_t>(a)] = std::move(ch);
  }
  const auto evaluate = [&](double log_tau, std::array<bool, 3>* axes) {
    const Eigen::VectorXd column = transient_column(rows, std::pow(10.0, log_tau));
    double delta = log_rows;  // the time constant
    int count = 0;
    for (int a = 0; a < 3; ++a) {
      const auto& ch = channels[static_cast<std::size_t>(a)];
      if (!ch) continue;
      Eigen::VectorXd col = ch->root_w.cwiseProduct(column);
      col -= ch->Q * (ch->Q.transpose() * col);
      const double norm2 = col.squaredNorm();
      if (!(norm2 > 0.0)) continue;
      const double removed = std::pow(ch->residual.dot(col), 2) / norm2;
      if (removed > log_rows) {
        delta += log_rows - removed;
        ++count;
        if (axes) (*axes)[static_cast<std::size_t>(a)] = true;
      }
    }
    return count > 0 ? delta : std::numeric_limits<double>::infinity();
  };
  double span = 0.0, shortest = std::numeric_limits<double>::infinity();
  for (const StepSummary& s : rows) {
    span = std::max(span, s.end_s);
    shortest = std::min(shortest, std::max(s.duration_s, 1.0));
  }
  const double lo = std::log10(std::max(1.0, shortest));
  const double hi = std::log10(std::max(10.0 * std::pow(10.0, lo), 3.0 * span));
  const auto [best_x, best] = tau_minimum([&](double x) { return evaluate(x, nullptr); }, lo, hi);
  if (!std::isfinite(best)) return std::nullopt;
  Form f;
  f.sensor = sensor;
  f.tau_s = std::stod(format_tau(std::pow(10.0, best_x)));
  f.expression = "exp(-elapsed/" + format_tau(f.tau_s) + ")";
  Screen screen;
  screen.delta_bic = evaluate(std::log10(f.tau_s), &screen.axes);
  if (!std::isfinite(screen.delta_bic)) return std::nullopt;
  return make_screened(f, screen);
}

/// The two rankings taken in turn, each term once, with the better of its two screenings (a
/// warm-up the wander swallowed screens weakly against the diagnosis's weights, strongly
/// against white noise or on the noise rows).
std::vector<Screened> interleave(const std::vector<Screened>& a, const std::vector<Screened>& b) {
  std::vector<Screened> out;
  std::map<std::string, std::size_t> position;
  for (std::size_t i = 0; i < std::max(a.size(), b.size()); ++i) {
    for (const auto* list : {&a, &b}) {
      if (i >= list->size()) continue;
      const Screened& s = (*list)[i];
      const auto [at, fresh] = position.emplace(s.key, out.size());
      if (fresh) {
        out.push_back(s);
      } else if (s.screen_delta_bic < out[at->second].screen_delta_bic) {
        out[at->second] = s;
      }
    }
  }
  return out;
}

/// Per sensor, the warm-up that came furthest (kept, then beating the wander, then the lowest
/// BIC against it, then screened), marked kept when it is among the suggestions.
std::vector<WarmUpCheck> best_warm_ups(std::vector<std::pair<core::TermSensor, WarmUpCheck>> checks,
                                       const std::vector<Suggestion>& suggestions) {
  for (auto& [sensor, check] : checks) {
    check.kept = std::any_of(suggestions.begin(), suggestions.end(),
                             [&](const Suggestion& s) { return s.custom == check.custom; });
  }
  const auto rank = [](const WarmUpCheck& c) {
    const double bic =
        std::isnan(c.delta_bic) ? std::numeric_limits<double>::infinity() : c.delta_bic;
    return std::tuple{!c.kept, !(c.beats_wander() && c.held_out_better), !c.beats_wander(), bic};
  };
  std::map<core::TermSensor, WarmUpCheck> best;
  for (auto& [sensor, check] : checks) {
    const auto at = best.find(sensor);
    if (at == best.end()) {
      best.emplace(sensor, std::move(check));
    } else if (rank(check) < rank(at->second)) {
      at->second = std::move(check);
    }
  }
  std::vector<WarmUpCheck> out;
  for (auto& [sensor, check] : best) out.push_back(std::move(check));
  return out;
}

/// A transient in elapsed time extrapolates in time, not in temperature.
bool in_elapsed_time(const Screened& c) {
  return c.form.tau_s > 0.0 || c.expression.find("elapsed") != std::string::npos;
}

}  // namespace

SuggestionSearch suggest_custom_terms(const SuggestInput& in, const FitOptions& options,
                                      const SuggestOptions& suggest) {
  SuggestionSearch out;
  out.ran = true;
  const std::vector<StepSummary>& steps = *in.steps;
  const FitResult& base = *in.fit;
  const Eigen::MatrixXd blocks = block_means(*in.data, in.model->earth_rate());
  const Eigen::MatrixXd segment_blocks =
      in.segments && !in.segments->empty()
          ? block_means(in.segments->segments, in.model->earth_rate())
          : Eigen::MatrixXd();

  // Screen every form on every sensor fitted, against the diagnosis's weights and against white
  // noise alone (the wander may hold the effect); keep the best of each distinct term.
  std::vector<core::TermSensor> sensors;
  if (options.rows != SensorRows::kAccel) sensors.push_back(core::TermSensor::kGyro);
  if (options.rows != SensorRows::kGyro) sensors.push_back(core::TermSensor::kAccel);
  const Whitened w = whiten(in, base, options);
  int forms = 0;
  std::vector<Screened> screened = screen_forms(w, blocks, steps, sensors, &forms);
  out.forms_tried = forms;
  if (base.noise.correlated()) {
    FitResult white_fit;
    try {
      white_fit = fit_model(steps, *in.model, StepNoise::white_only(base.noise.white, ""), options);
      int ignored = 0;
      screened = interleave(
          screened, screen_forms(whiten(in, white_fit, options), blocks, steps, sensors, &ignored));
    } catch (const core::InputError&) {
      // the model's fit succeeded with the wander: it does with white weights too
    }
  }

  // Hundreds of forms were tried: the best of them lowers BIC by about 2 ln(forms) on noise
  // alone, so that much is asked on top of very strong evidence. And a catalogue term, with
  // its physics and units, is preferred unless the custom term is very strongly better: in a
  // thermal campaign `elapsed` follows the temperature plateaus and nearly ties with a
  // temperature term.
  const double bar =
      std::min(in.best_catalogue_delta_bic + kStrongDeltaBic,
               kStrongDeltaBic - 2.0 * std::log(static_cast<double>(out.forms_tried)));
  // The transients the noise rows show (a long capture's segments), checked first.
  std::vector<Screened> on_rows;
  for (core::TermSensor sensor : sensors) {
    if (auto t = transient_on_noise_rows(in, sensor, options)) on_rows.push_back(std::move(*t));
  }
  std::stable_sort(on_rows.begin(), on_rows.end(), [](const Screened& a, const Screened& b) {
    return a.screen_delta_bic < b.screen_delta_bic;
  });
  screened = interleave(on_rows, screened);
  // A form enters the checks when either screening sees it lower BIC by the look-elsewhere bar.
  const double screen_bar = kStrongDeltaBic - 2.0 * std::log(static_cast<double>(out.forms_tried));
  // The held-out check runs on the noise rows, with the model's columns (on the steps when the
  // rows cannot give them: a model without the Earth rate, whose reference differs).
  std::vector<StepSummary> held_rows;
  try {
    held_rows = select_parameters(in.evidence->rows(), in.evidence->superset(), *in.model);
  } catch (const std::invalid_argument&) {
    held_rows.clear();
  }
  const Folds held_plateau_folds = make_folds(held_rows.empty() ? steps : held_rows, true);
  const Folds held_step_folds = make_folds(held_rows.empty() ? steps : held_rows, false);
  const double transient_bar =
      std::min(in.best_catalogue_delta_bic + kStrongDeltaBic,
               in.evidence->wander_known() ? kStrongDeltaBicKnownWander : kStrongDeltaBic);
  double run_span_s = 0.0;
  for (const StepSummary& s : steps) run_span_s = std::max(run_span_s, s.end_s);
  // The bar a form is judged by: a warm-up that settles within the run is the one form stated
  // before the search, tested on its own without the search's look-elsewhere cost (the seed's
  // power-on and warm-up tests: the commonest effect a real IMU has); every other form, a
  // slower decay included, pays it.
  const auto bar_of = [&](const Form& f) {
    return f.tau_s > 0.0 && f.tau_s <= kWarmUpSettlesWithinRun * run_span_s ? transient_bar : bar;
  };
  std::string folds_used;
  std::set<std::string> keys, names;
  for (const auto& c : in.model->customs()) names.insert(c.name);
  std::string best_rejected;
  std::size_t checked = 0;
  struct Passed {
    Suggestion s;
    double tau_s;
    CustomTermSpec spec;
  };
  std::vector<Passed> passed;
  // Every warm-up transient judged, with its sensor: the best per sensor is reported.
  std::vector<std::pair<core::TermSensor, WarmUpCheck>> warm_ups;
  // The bar a check names: its own where it was weighed (a known wander's may be the catalogue's
  // given the term), else its form's.
  const auto note_warm_up = [&](const Screened& c, WarmUpCheck check) {
    check.tau_s = c.form.tau_s;
    if (check.bar == 0.0) check.bar = bar_of(c.form);
    warm_ups.emplace_back(c.form.sensor, std::move(check));
  };
  // The wander alone, per set of channels a term acts on (the hypothesis without the term).
  std::map<std::array<bool, kChannels>, Hypothesis> without_term;
  for (const Screened& c : screened) {
    // The transient of each screening is checked (each weighting finds its own time constant,
    // and only the comparison against the wander can tell which holds): they are a few, and do
    // not count against the forms checked.
    const bool transient = c.form.tau_s > 0.0;
    if (!transient &&
        (checked >= suggest.max_checked || passed.size() >= suggest.max_suggestions)) {
      continue;
    }
    if (!keys.insert(c.key).second) continue;
    if (c.screen_delta_bic >= screen_bar) {
      if (transient) {
        WarmUpCheck check;
        check.custom = sensor_text(c.form.sensor, c.axes) + ":" + c.expression;
        check.two_log_likelihood_ratio = std::numeric_limits<double>::quiet_NaN();
        check.delta_bic = std::numeric_limits<double>::quiet_NaN();
        check.verdict = fmt::format(
            "screened out: it would change BIC by {:+.0f} against the model's weights or white "
            "noise (below {:.0f} is asked before the wander is weighed)",
            c.screen_delta_bic, screen_bar);
        note_warm_up(c, std::move(check));
      }
      if (best_rejected.empty()) {
        best_rejected = fmt::format(
            "the best, {}:{}, would change BIC by {:+.0f} (below {:.0f} "
            "is asked)",
            sensor_text(c.form.sensor, c.axes), c.expression, c.screen_delta_bic, screen_bar);
      }
      continue;
    }
    if (!transient) ++checked;
    const std::string name = name_of(c.expression, names);
    CustomTermSpec spec;
    spec.name = name;
    spec.sensor = c.form.sensor;
    spec.expression = c.expression;
    spec.axes = c.axes;
    const std::string text = spec.text();
    Model with;
    try {
      with = in.model->with_custom(parse_custom_term(text, "suggested custom term " + text));
    } catch (const core::InputError&) {
      continue;  // cannot happen for the forms built here; never suggest what fit would refuse
    }
    const std::vector<StepSummary> aug =
        with_columns(steps, spec.sensor, spec.axes, form_columns(c.form, blocks, steps));
    FitResult exact;
    try {
      exact = fit_model(aug, with, base.noise, options);
    } catch (const core::InputError&) {
      continue;
    }
    Suggestion s;
    s.custom = text;
    s.added_parameters =
        static_cast<int>(exact.parameters.size()) - static_cast<int>(base.parameters.size());
    if (s.added_parameters <= 0) continue;
    const int linear = s.added_parameters;
    if (c.form.tau_s > 0.0) ++s.added_parameters;
    // The term against the wander, each with the noise re-estimated under it.
    std::array<Eigen::MatrixXd, kChannels> extra;
    const int first = spec.sensor == core::TermSensor::kGyro ? kGx : kAx;
    const Eigen::MatrixXd V = evidence_form_columns(c.form, blocks, segment_blocks, in);
    std::array<bool, kChannels> acting{};
    for (int a = 0; a < 3; ++a) {
      if (!spec.axes[static_cast<std::size_t>(a)]) continue;
      extra[static_cast<std::size_t>(first + a)] = V.col(a);
      acting[static_cast<std::size_t>(first + a)] = true;
    }
    const Hypothesis with_term = in.evidence->with_columns(extra, c.form.tau_s > 0.0 ? 1 : 0);
    auto found = without_term.find(acting);
    if (found == without_term.end()) {
      found = without_term.emplace(acting, in.evidence->base(acting)).first;
    }
    s.delta_bic = delta_bic(with_term, found->second);
    // The noise that remains with the term: re-estimated on the channels it acts on, the
    // diagnosis's elsewhere.
    StepNoise remaining = base.noise;
    for (int ch = 0; ch < kChannels; ++ch) {
      if (with_term.scored[static_cast<std::size_t>(ch)]) {
        remaining.channels[static_cast<std::size_t>(ch)] =
            with_term.noise.channels[static_cast<std::size_t>(ch)];
      }
    }
    if (exact.dof > 0 && exact.chi2 > 0.0) {
      const FitResult exact_remaining = fit_model(aug, with, remaining, options);
      const FitResult base_remaining = fit_model(steps, *in.model, remaining, options);
      const double F = ((base_remaining.chi2 - exact_remaining.chi2) / linear) /
                       (exact_remaining.chi2 / exact_remaining.dof);
      const boost::math::fisher_f_distribution<double> dist(linear, exact_remaining.dof);
      s.p_value = F > 0.0 ? boost::math::cdf(boost::math::complement(dist, F)) : 1.0;
    }
    double form_bar = bar_of(c.form);
    // With the wander known, a catalogue term is weighed by what it adds once the warm-up is
    // there: alone, a temperature order takes the plateau offset a warm-up leaves (a white-noise
    // unit's 10x warm-up of 1800 s: -1394 against the wander alone, where the decay itself gave
    // -228 beyond every catalogue term).
    if (transient && in.evidence->wander_known() && form_bar == transient_bar) {
      double given = std::numeric_limits<double>::infinity();
      const int nonlinear = c.form.tau_s > 0.0 ? 1 : 0;
      for (const std::vector<std::string>& term : in.catalogue_terms) {
        const std::array<bool, kChannels> on = in.evidence->channels_of(term);
        given = std::min(given, delta_bic(in.evidence->with_columns_on(on, extra, nonlinear),
                                          in.evidence->without(term, extra, nonlinear)));
      }
      s.catalogue_delta_bic_given = given;
      form_bar = std::min(given + kStrongDeltaBic, kStrongDeltaBicKnownWander);
    }
    WarmUpCheck check;
    if (transient) {
      check.custom = text;
      check.two_log_likelihood_ratio =
          2.0 * (with_term.log_likelihood - found->second.log_likelihood);
      check.noise_penalty_change = with_term.noise_penalty - found->second.noise_penalty;
      check.delta_bic = s.delta_bic;
      check.bar = form_bar;
    }
    if (!(s.delta_bic < form_bar)) {
      if (transient) {
        check.verdict = fmt::format(
            "within what the wander makes: BIC {:+.1f} against it (2 ln LR {:.1f}, the wanders' "
            "cost change {:+.1f}; below {:.0f} is asked)",
            s.delta_bic, check.two_log_likelihood_ratio, check.noise_penalty_change, form_bar);
        note_warm_up(c, std::move(check));
      }
      if (best_rejected.empty()) {
        best_rejected = fmt::format(
            "the best, {}, changes BIC by {:+.0f} against the wander (below {:.0f} is asked)", text,
            s.delta_bic, form_bar);
      }
      continue;
    }
    // Held out, on the noise rows (a long capture by its segments, where a warm-up may be all
    // there is to see), against the noise that remains with the term (the wander without it
    // may hold the effect, and would excuse the model's misses on the held-out part).
    const bool held_on_rows = !held_rows.empty();
    const std::vector<StepSummary>& held_steps = held_on_rows ? held_rows : steps;
    const Folds* folds = in_elapsed_time(c) ? &held_step_folds : &held_plateau_folds;
    auto held_before = held_out_chi2(held_steps, *in.model, remaining, options, *folds);
    // Without one of its plateaus the run may not determine the model (a temperature term
    // needs two): hold out steps instead.
    if (!std::isfinite(held_before.first) && folds == &held_plateau_folds) {
      folds = &held_step_folds;
      held_before = held_out_chi2(held_steps, *in.model, remaining, options, *folds);
    }
    if (!std::isfinite(held_before.first)) {
      best_rejected =
          "the run is too small to fit the model with a part of it held out, so no "
          "custom term can be checked";
      break;
    }
    const std::vector<StepSummary> held_aug =
        held_on_rows ? with_columns(held_rows, spec.sensor, spec.axes, V) : aug;
    const auto [held_after, rows_after] = held_out_chi2(held_aug, with, remaining, options, *folds);
    s.held_out = folds->how;
    s.held_out_chi2_dof_before = held_before.second > 0 ? held_before.first / held_before.second
                                                        : std::numeric_limits<double>::quiet_NaN();
    s.held_out_chi2_dof_after =
        rows_after > 0 ? held_after / rows_after : std::numeric_limits<double>::quiet_NaN();
    // A column fitted to noise raises the held-out chi-square by about its parameters; a real
    // effect lowers it by about what it removes in the fit.
    check.held_out_better = held_after < held_before.first - linear;
    if (!check.held_out_better) {
      if (transient) {
        check.verdict = fmt::format(
            "beats the wander (BIC {:+.1f}) but does not hold on held-out data (chi2/dof {:.3g} "
            "-> {:.3g}, {})",
            s.delta_bic, s.held_out_chi2_dof_before, s.held_out_chi2_dof_after, folds->how);
        note_warm_up(c, std::move(check));
      }
      if (best_rejected.empty()) {
        best_rejected = fmt::format(
            "the best, {}, does not hold on held-out data (chi2/dof {:.3g} "
            "-> {:.3g}, {})",
            text, s.held_out_chi2_dof_before, s.held_out_chi2_dof_after, folds->how);
      }
      continue;
    }
    folds_used = folds->how;
    if (transient) {
      check.verdict = fmt::format(
          "beats the wander (BIC {:+.1f}, 2 ln LR {:.1f}) and holds on held-out data (chi2/dof "
          "{:.3g} -> {:.3g}, {})",
          s.delta_bic, check.two_log_likelihood_ratio, s.held_out_chi2_dof_before,
          s.held_out_chi2_dof_after, folds->how);
      note_warm_up(c, std::move(check));
    }
    names.insert(name);
    passed.push_back({std::move(s), c.form.tau_s, spec});
  }
  // One transient per sensor and axes: the one that beats the wander by most.
  std::stable_sort(passed.begin(), passed.end(),
                   [](const Passed& a, const Passed& b) { return a.s.delta_bic < b.s.delta_bic; });
  std::set<std::string> transients;
  std::vector<Passed> kept;
  for (Passed& p : passed) {
    if (p.tau_s > 0.0 && !transients.insert(sensor_text(p.spec.sensor, p.spec.axes)).second) {
      continue;
    }
    if (kept.size() < suggest.max_suggestions) kept.push_back(std::move(p));
  }
  passed = std::move(kept);
  // The figures reported are those of the path `calstand fit --custom` takes.
  for (Passed& p : passed) {
    const Model with =
        in.model->with_custom(parse_custom_term(p.s.custom, "--custom " + p.s.custom));
    try {
      p.s.fit = fit_run(*in.data, with, options,
                        in.noise_options ? *in.noise_options : NoiseEstimateOptions{});
    } catch (const core::InputError&) {
      continue;
    }
    // Its chi2/dof may be above the model's: the model's weights hold the wander that may have
    // swallowed the effect, the term's do not. The comparison was made above, on one footing.
    p.s.chi2_dof_after = p.s.fit.chi2_dof;
    p.s.effect = effect_words(p.spec, p.s.fit, p.tau_s);
    out.suggestions.push_back(std::move(p.s));
  }
  std::stable_sort(
      out.suggestions.begin(), out.suggestions.end(),
      [](const Suggestion& a, const Suggestion& b) { return a.delta_bic < b.delta_bic; });
  out.warm_ups = best_warm_ups(std::move(warm_ups), out.suggestions);
  if (!out.suggestions.empty()) {
    out.summary = fmt::format(
        "{} custom forms built from the signals tried; {} pass the guards (BIC against the wander "
        "below {:.0f}, {:.0f} for a warm-up transient, and better predictions of held-out data "
        "with {})",
        out.forms_tried, out.suggestions.size(), bar, transient_bar, folds_used);
  } else {
    out.summary = fmt::format(
        "none of the {} custom forms built from the signals (each signal, its square and abs(), "
        "products of two, each axis on its own axis's signal, exp(-elapsed/tau)) both earns its "
        "parameters and holds on held-out data{}",
        out.forms_tried, best_rejected.empty() ? std::string() : "; " + best_rejected);
  }
  return out;
}

}  // namespace calstand::solver

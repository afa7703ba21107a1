#include "solver/model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <functional>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/site.hpp"
#include "core/suggest.hpp"
#include "core/text.hpp"
#include "term_kind.hpp"

namespace calstand::solver {

using detail::TermKind;

namespace {

constexpr int kMaxTemperatureOrder = 9;

std::string term_name(const core::ErrorTermInfo& info, int order) {
  return info.polynomial_order && order != 1 ? fmt::format("{}:{}", info.name, order)
                                             : std::string(info.name);
}

std::string unknown_term_message(std::string_view name,
                                 const std::vector<CustomTermSpec>& customs) {
  std::vector<std::string_view> names;
  for (const auto& t : core::error_term_catalogue()) names.push_back(t.name);
  for (const auto& c : customs) names.push_back(c.name);
  const std::string best = core::closest_name(name, names);
  return fmt::format("unknown error term \"{}\"{}", name,
                     best.empty() ? std::string(" (see `calstand fit --help` for the catalogue)")
                                  : fmt::format(" (did you mean \"{}\"?)", best));
}

TermKind kind_of_name(std::string_view n) {
  if (n == "gyro_bias" || n == "accel_bias") return TermKind::kBias;
  if (n == "gyro_scale" || n == "accel_scale") return TermKind::kScale;
  if (n == "gyro_misalignment" || n == "accel_misalignment") return TermKind::kMisalignment;
  if (n == "gyro_scale_asymmetry" || n == "accel_scale_asymmetry") return TermKind::kAsymmetry;
  if (n == "gyro_quadratic") return TermKind::kGyroQuadratic;
  if (n == "accel_quadratic") return TermKind::kAccelQuadratic;
  if (n == "gyro_g_sensitivity") return TermKind::kGSensitivity;
  if (n == "gyro_temp_bias" || n == "accel_temp_bias") return TermKind::kTempBias;
  if (n == "gyro_temp_scale" || n == "accel_temp_scale") return TermKind::kTempScale;
  if (n == "accel_lever_arm") return TermKind::kLeverArm;
  if (n == "table_tilt") return TermKind::kTilt;
  return TermKind::kNoParameters;  // earth_rate changes the reference (SignalBuilder)
}

}  // namespace

namespace detail {

TermKind term_kind(const core::ErrorTermInfo* info) {
  static const std::vector<core::ErrorTermInfo>& catalogue = core::error_term_catalogue();
  static const std::vector<TermKind> kinds = [] {
    std::vector<TermKind> out;
    for (const auto& t : catalogue) out.push_back(kind_of_name(t.name));
    return out;
  }();
  const std::less<const core::ErrorTermInfo*> before;
  if (!before(info, catalogue.data()) && before(info, catalogue.data() + catalogue.size())) {
    return kinds[static_cast<std::size_t>(info - catalogue.data())];
  }
  return kind_of_name(info->name);
}

}  // namespace detail

std::string_view channel_name(int channel) {
  static constexpr std::string_view kNames[kChannels] = {"gx", "gy", "gz", "ax", "ay", "az"};
  return kNames[channel];
}

Model Model::parse(std::string_view terms, const std::vector<std::string>& custom_texts) {
  std::vector<CustomTermSpec> customs;
  for (const auto& text : custom_texts) {
    CustomTermSpec spec = parse_custom_term(text, "--custom " + text);
    for (const auto& c : customs) {
      if (c.name == spec.name) {
        throw core::InputError("--custom " + text, "custom term \"" + spec.name + "\" given twice");
      }
    }
    customs.push_back(std::move(spec));
  }
  std::vector<ModelTerm> list;
  std::vector<bool> custom_listed(customs.size(), false);
  std::size_t start = 0;
  while (start <= terms.size()) {
    const std::size_t comma = std::min(terms.find(',', start), terms.size());
    const std::string_view item = core::trim_blanks(terms.substr(start, comma - start));
    start = comma + 1;
    if (item.empty()) {
      if (comma >= terms.size() && list.empty() && customs.empty()) {
        throw core::InputError("--model", "no terms given");
      }
      if (comma >= terms.size()) break;
      continue;
    }
    const std::string where = fmt::format("--model term \"{}\"", item);
    const std::size_t colon = item.find(':');
    const std::string_view name = item.substr(0, colon);
    ModelTerm term;
    term.name = std::string(name);
    if (const auto* info = core::find_error_term(name)) {
      term.info = info;
      if (colon != std::string_view::npos) {
        const std::string_view digits = item.substr(colon + 1);
        int order = 0;
        const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), order);
        if (!info->polynomial_order) {
          throw core::InputError(where, fmt::format("only temperature bias terms take an order "
                                                    "(gyro_temp_bias:N, accel_temp_bias:N)"));
        }
        if (ec != std::errc{} || end != digits.data() + digits.size() || order < 1 ||
            order > kMaxTemperatureOrder) {
          throw core::InputError(where, fmt::format("order \"{}\" must be an integer 1..{}", digits,
                                                    kMaxTemperatureOrder));
        }
        term.order = order;
      }
      term.name = term_name(*info, term.order);
    } else {
      bool found = false;
      for (std::size_t c = 0; c < customs.size(); ++c) {
        if (customs[c].name == name && colon == std::string_view::npos) {
          term.custom = static_cast<int>(c);
          custom_listed[c] = true;
          found = true;
        }
      }
      if (!found) throw core::InputError("--model", unknown_term_message(name, customs));
    }
    for (const auto& t : list) {
      if ((term.info && t.info == term.info) || (term.custom >= 0 && t.custom == term.custom)) {
        throw core::InputError(where, "term given twice");
      }
    }
    list.push_back(std::move(term));
  }
  // A custom term given with --custom belongs to the model even when not listed in --model.
  for (std::size_t c = 0; c < customs.size(); ++c) {
    if (!custom_listed[c]) {
      ModelTerm t;
      t.custom = static_cast<int>(c);
      t.name = customs[c].name;
      list.push_back(std::move(t));
    }
  }
  return Model(std::move(list), std::move(customs));
}

Model::Model(std::vector<ModelTerm> terms, std::vector<CustomTermSpec> customs)
    : terms_(std::move(terms)), customs_(std::move(customs)) {
  for (const auto& c : customs_) evaluators_.push_back(std::make_shared<CustomTermEvaluator>(c));
  index_parameters();
}

void Model::index_parameters() {
  parameters_.clear();
  first_parameter_.clear();
  earth_rate_ = false;
  for (const auto& t : terms_) {
    first_parameter_.push_back(parameters_.size());
    if (t.info) {
      if (t.info->name == "earth_rate") earth_rate_ = true;
      for (const auto& n : core::parameter_names(*t.info, t.order)) {
        parameters_.push_back({n, std::string(t.info->unit), t.name, t.info->sensor});
      }
    } else {
      const CustomTermSpec& c = customs_[static_cast<std::size_t>(t.custom)];
      const std::string unit = fmt::format(
          "{}/({})", c.sensor == core::TermSensor::kGyro ? "deg/s" : "m/s^2", c.expression);
      for (int a = 0; a < 3; ++a) {
        if (!c.axes[static_cast<std::size_t>(a)]) continue;
        parameters_.push_back({c.name + "." + "xyz"[a], unit, t.name, c.sensor});
      }
    }
  }
}

const ModelTerm* Model::find(std::string_view name) const {
  for (const auto& t : terms_) {
    if ((t.info && t.info->name == name) || (!t.info && t.name == name)) return &t;
  }
  return nullptr;
}

std::string Model::text() const {
  std::string out;
  for (const auto& t : terms_) out += (out.empty() ? "" : ",") + t.name;
  return out;
}

std::pair<std::size_t, std::size_t> Model::parameter_range(std::size_t t) const {
  const std::size_t first = first_parameter_.at(t);
  const std::size_t end = t + 1 < terms_.size() ? first_parameter_[t + 1] : parameters_.size();
  return {first, end - first};
}

Model Model::with_term(const core::ErrorTermInfo& info, int order) const {
  Model m = *this;
  for (auto& t : m.terms_) {
    if (t.info == &info) {
      t.order = order;
      t.name = term_name(info, order);
      m.index_parameters();
      return m;
    }
  }
  ModelTerm t;
  t.info = &info;
  t.order = order;
  t.name = term_name(info, order);
  m.terms_.push_back(std::move(t));
  m.index_parameters();
  return m;
}

Model Model::with_custom(const CustomTermSpec& spec) const {
  Model m = *this;
  m.customs_.push_back(spec);
  m.evaluators_.push_back(std::make_shared<CustomTermEvaluator>(spec));
  ModelTerm t;
  t.custom = static_cast<int>(m.customs_.size() - 1);
  t.name = spec.name;
  m.terms_.push_back(std::move(t));
  m.index_parameters();
  return m;
}

Eigen::Matrix<double, kChannels, 1> Model::reference(const Signals& s) const {
  Eigen::Matrix<double, kChannels, 1> r;
  r << s.rate_dps, s.force_mps2;
  return r;
}

void Model::regressors(const Signals& s, Eigen::Ref<Eigen::MatrixXd> out) const {
  // A plain matrix (the usual caller) is zeroed as one block: element by element through the
  // strided reference it took a fifth of a fit's time.
  if (out.outerStride() == out.rows()) {
    std::fill_n(out.data(), out.size(), 0.0);
  } else {
    out.setZero();
  }
  const Eigen::Vector3d& w = s.rate_dps;
  const Eigen::Vector3d& f = s.force_mps2;
  constexpr double g0 = core::kStandardGravity;
  constexpr double ppm = 1e-6;
  for (std::size_t ti = 0; ti < terms_.size(); ++ti) {
    const ModelTerm& t = terms_[ti];
    Eigen::Index p = static_cast<Eigen::Index>(first_parameter_[ti]);
    if (!t.info) {
      const CustomTermSpec& c = customs_[static_cast<std::size_t>(t.custom)];
      const Eigen::Vector3d e = (*evaluators_[static_cast<std::size_t>(t.custom)])(s);
      const int row = c.sensor == core::TermSensor::kGyro ? kGx : kAx;
      for (int i = 0; i < 3; ++i) {
        if (c.axes[static_cast<std::size_t>(i)]) out(row + i, p++) = e[i];
      }
      continue;
    }
    const bool gyro = t.info->sensor == core::TermSensor::kGyro;
    const int row = gyro ? kGx : kAx;
    const Eigen::Vector3d& in = gyro ? w : f;  // the sensor's own input
    switch (detail::term_kind(t.info)) {
      case TermKind::kBias:
        for (int i = 0; i < 3; ++i) out(row + i, p + i) = 1.0;
        break;
      case TermKind::kScale:
        for (int i = 0; i < 3; ++i) out(row + i, p + i) = ppm * in[i];
        break;
      case TermKind::kMisalignment:
        // Components xy xz yx yz zx zy: M[i][j] couples input j into axis i.
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) {
            if (i != j) out(row + i, p++) = in[j];
          }
        }
        break;
      case TermKind::kAsymmetry:
        for (int i = 0; i < 3; ++i) out(row + i, p + i) = ppm * std::abs(in[i]);
        break;
      case TermKind::kGyroQuadratic:
        for (int i = 0; i < 3; ++i) out(row + i, p + i) = ppm * w[i] * w[i];
        break;
      case TermKind::kAccelQuadratic:
        for (int i = 0; i < 3; ++i) out(row + i, p + i) = ppm * g0 * (f[i] / g0) * (f[i] / g0);
        break;
      case TermKind::kGSensitivity:
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) out(kGx + i, p++) = f[j] / g0;
        }
        break;
      case TermKind::kTempBias: {
        double power = 1.0;
        for (int k = 1; k <= t.order; ++k) {
          power *= s.dT_c;
          for (int i = 0; i < 3; ++i) out(row + i, p++) = power;
        }
        break;
      }
      case TermKind::kTempScale:
        for (int i = 0; i < 3; ++i) out(row + i, p + i) = ppm * s.dT_c * in[i];
        break;
      case TermKind::kLeverArm: {
        // wt x (wt x r) + dwt/dt x r = ([wt x]^2 + [dwt/dt x]) r, rates in rad/s. Within a step
        // the axis rates are constant; dwt/dt is the outer axis carrying the inner one.
        const Eigen::Vector3d wt = s.table_rate_dps * core::kDegToRad;
        const Eigen::Vector3d alpha = s.table_accel_dps2 * core::kDegToRad;
        const Eigen::Matrix3d K = core::skew(wt);
        out.block(kAx, p, 3, 3) = K * K + core::skew(alpha);
        break;
      }
      case TermKind::kTilt: {
        // f = C_BL (I - [t x]) f_L, so df/dt_k = C_BL (f_L x e_k). The tilted base turns the
        // Earth rate with gravity; that part enters the gyro rows when the model has earth_rate.
        const Eigen::Vector3d f_L = s.C_BL.transpose() * f;
        const Eigen::Vector3d w_L = s.C_BL.transpose() * s.earth_rate_dps;
        for (int k = 0; k < 2; ++k) {
          const Eigen::Vector3d e = Eigen::Vector3d::Unit(k);
          out.block(kAx, p + k, 3, 1) = s.C_BL * f_L.cross(e);
          if (earth_rate_) out.block(kGx, p + k, 3, 1) = s.C_BL * w_L.cross(e);
        }
        break;
      }
      case TermKind::kNoParameters:  // earth_rate: it changes the reference (SignalBuilder)
        break;
    }
  }
}

}  // namespace calstand::solver

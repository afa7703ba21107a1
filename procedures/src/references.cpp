#include "references.hpp"

#include <fmt/format.h>

#include <cmath>
#include <regex>

namespace calstand::procedures::detail {
namespace {

const std::regex& reference_pattern() {
  static const std::regex re(R"(^(-?)\$\{([A-Za-z_][A-Za-z0-9_]*)\}$)");
  return re;
}

const std::regex& label_pattern() {
  static const std::regex re(R"(\$\{([A-Za-z_][A-Za-z0-9_]*)\})");
  return re;
}

}  // namespace

std::optional<Reference> parse_reference(const nlohmann::json& value) {
  if (!value.is_string()) return std::nullopt;
  const auto& s = value.get_ref<const std::string&>();
  std::smatch m;
  if (!std::regex_match(s, m, reference_pattern())) return std::nullopt;
  return Reference{m[2].str(), m[1].length() > 0};
}

std::vector<std::string> label_references(const std::string& text) {
  std::vector<std::string> names;
  for (std::sregex_iterator it(text.begin(), text.end(), label_pattern()), end; it != end; ++it) {
    names.push_back((*it)[1].str());
  }
  return names;
}

std::string fill_label(
    const std::string& text,
    const std::function<std::optional<nlohmann::json>(const std::string&)>& lookup) {
  std::string out;
  auto last = text.cbegin();
  for (std::sregex_iterator it(text.begin(), text.end(), label_pattern()), end; it != end; ++it) {
    const auto& m = *it;
    out.append(last, m[0].first);
    const auto value = lookup(m[1].str());
    out += value ? format_value(*value) : m[0].str();
    last = m[0].second;
  }
  out.append(last, text.cend());
  return out;
}

std::string format_number(double x) {
  if (std::isfinite(x) && x == std::trunc(x) && std::abs(x) < 1e15) {
    return std::to_string(static_cast<long long>(x));
  }
  return fmt::format("{}", x);  // shortest text that reads back as x
}

std::string format_value(const nlohmann::json& value) {
  if (value.is_number_integer()) return std::to_string(value.get<long long>());
  if (value.is_number()) return format_number(value.get<double>());
  if (value.is_string()) return value.get<std::string>();
  if (value.is_array()) {
    std::string out = "[";
    for (std::size_t i = 0; i < value.size(); ++i) {
      if (i > 0) out += ", ";
      out += quote_value(value[i]);
    }
    return out + "]";
  }
  return value.dump();
}

std::string quote_value(const nlohmann::json& value) {
  if (value.is_string()) return value.dump();
  return format_value(value);
}

}  // namespace calstand::procedures::detail

#include "procedures/procedure.hpp"

namespace calstand::procedures::detail {

std::string shown_value(const Step& step, const std::string& field, double value) {
  const auto it = step.references.find(field);
  if (it == step.references.end()) return format_number(value);
  return it->second + " = " + format_number(value);
}

}  // namespace calstand::procedures::detail

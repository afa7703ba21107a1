// GET /catalogue's content: the contract's terms and the solver's signals, nothing left out.
#include "analysis/catalogue.hpp"

#include <gtest/gtest.h>

#include "core/error_terms.hpp"
#include "solver/custom_term.hpp"
#include "solver/signals.hpp"

namespace calstand::analysis {
namespace {

TEST(Catalogue, ListsEveryTermWithItsSensorUnitOrderAndEffect) {
  const nlohmann::json j = catalogue_json();
  const auto& terms = j.at("terms");
  ASSERT_EQ(terms.size(), core::error_term_catalogue().size());
  for (std::size_t i = 0; i < terms.size(); ++i) {
    const auto& info = core::error_term_catalogue()[i];
    EXPECT_EQ(terms[i].at("name"), std::string(info.name));
    EXPECT_EQ(terms[i].at("unit"), std::string(info.unit));
    EXPECT_EQ(terms[i].at("ordered"), info.polynomial_order);
    EXPECT_FALSE(terms[i].at("effect").get<std::string>().empty());
    const std::string sensor = terms[i].at("sensor");
    EXPECT_TRUE(sensor == "gyro" || sensor == "accel" || sensor == "both") << sensor;
    if (info.name.starts_with("gyro_")) {
      EXPECT_EQ(sensor, "gyro") << info.name;
    }
    if (info.name.starts_with("accel_")) {
      EXPECT_EQ(sensor, "accel") << info.name;
    }
  }
}

TEST(Catalogue, EverySignalItListsCompilesInACustomTerm) {
  const nlohmann::json j = catalogue_json();
  const auto& signals = j.at("signals");
  ASSERT_EQ(signals.size(), solver::signal_names().size());
  for (std::size_t i = 0; i < signals.size(); ++i) {
    const std::string name = signals[i].at("name");
    EXPECT_EQ(name, std::string(solver::signal_names()[i]));
    EXPECT_FALSE(signals[i].at("unit").get<std::string>().empty());
    EXPECT_FALSE(signals[i].at("meaning").get<std::string>().empty());
    EXPECT_NO_THROW(solver::parse_custom_term("k=gyro:" + name, "test")) << name;
  }
}

}  // namespace
}  // namespace calstand::analysis

#include "core/state_json.hpp"

#include <gtest/gtest.h>

namespace calstand::core {
namespace {

TEST(StateJson, TableSaysWhetherItsLinkIsLostAndWhyOnlyWhileFaulted) {
  TableState t;
  t.time_s = 12.5;
  t.outer.angle_deg = 90.0;
  auto j = to_json(t);
  EXPECT_EQ(j["time_s"], 12.5);
  EXPECT_EQ(j["link_lost"], false);
  EXPECT_FALSE(j["outer"].contains("fault_text"));

  t.link_lost = true;
  t.outer.fault = t.inner.fault = true;
  t.outer.fault_text = t.inner.fault_text = "table state unreadable: no reply";
  j = to_json(t);
  EXPECT_EQ(j["link_lost"], true);
  EXPECT_EQ(j["outer"]["angle_deg"], 90.0) << "the last known angle";
  EXPECT_EQ(j["outer"]["fault_text"], "table state unreadable: no reply");
}

TEST(StateJson, ChamberSaysWhetherItsLinkIsLost) {
  ChamberState c;
  c.air_temperature_c = 25.0;
  EXPECT_EQ(to_json(c)["link_lost"], false);
  c.fault = true;
  c.link_lost = true;
  c.fault_text = "link down: connection refused";
  const auto j = to_json(c);
  EXPECT_EQ(j["link_lost"], true);
  EXPECT_EQ(j["air_c"], 25.0);
  EXPECT_EQ(j["fault_text"], "link down: connection refused");
}

}  // namespace
}  // namespace calstand::core

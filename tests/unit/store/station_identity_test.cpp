#include "store/station_identity.hpp"

#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "store/error.hpp"
#include "temp_dir.hpp"

namespace calstand::store {
namespace {

using testing::TempDir;

TEST(StationIdentity, EachNewDatabaseHasItsOwnVersion4UuidThatStaysAcrossOpens) {
  TempDir dir;
  std::string first;
  {
    Database db(dir.file("a.db"));
    first = station_uuid(db);
  }
  const std::regex v4("[0-9a-f]{8}-[0-9a-f]{4}-4[0-9a-f]{3}-[89ab][0-9a-f]{3}-[0-9a-f]{12}");
  EXPECT_TRUE(std::regex_match(first, v4)) << first;
  Database again(dir.file("a.db"));
  EXPECT_EQ(station_uuid(again), first);
  Database other(dir.file("b.db"));
  EXPECT_NE(station_uuid(other), first);
}

TEST(StationIdentity, AMissingIdentityIsAStoreErrorNamingTheFile) {
  TempDir dir;
  Database db(dir.file("a.db"));
  db.sql().exec("DELETE FROM station_identity");
  try {
    station_uuid(db);
    FAIL() << "no error";
  } catch (const StoreError& e) {
    EXPECT_NE(std::string(e.what()).find("a.db has no station identity"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace calstand::store

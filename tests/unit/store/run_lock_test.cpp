// Which process drives a run: the run lock, and runs cut off without one reading `interrupted`.
#include "store/run_lock.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "store/database.hpp"
#include "store/database_lock.hpp"
#include "store/run_store.hpp"

namespace calstand::store {
namespace {

std::string fresh_db(const std::string& name) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("calstand-run-lock-" + std::to_string(::getpid()) + "-" + name + ".db");
  for (const char* suffix : {"", "-wal", "-shm", ".lock"})
    std::filesystem::remove(path.string() + suffix);
  return path.string();
}

TEST(RunLock, OneHolderPerRunAndNoneOnceReleased) {
  const std::string db = fresh_db("holders");
  EXPECT_FALSE(RunLock::held(db, 3));
  {
    const RunLock lock(db, 3);
    EXPECT_TRUE(RunLock::held(db, 3));
    EXPECT_FALSE(RunLock::held(db, 4)) << "runs are locked one by one";
    // Another descriptor, even of this process, is another driver.
    EXPECT_THROW(RunLock(db, 3), DatabaseBusy);
    const RunLock other(db, 4);
    EXPECT_TRUE(RunLock::held(db, 4));
  }
  EXPECT_FALSE(RunLock::held(db, 3));
  EXPECT_FALSE(RunLock::held(db, 4));
  // The database's own flock on the same file does not interfere.
  const DatabaseLock exclusive(db, DatabaseLock::Mode::kExclusive, "test");
  const RunLock lock(db, 3);
  EXPECT_TRUE(RunLock::held(db, 3));
  EXPECT_TRUE(RunLock::held(":memory:", 3)) << "cannot tell: not claimed cut off";
}

TEST(RunLock, ARunLeftRunningWithoutItsDriverReadsInterrupted) {
  const std::string db = fresh_db("cut-off");
  Database database(db);
  RunStore runs(database);
  NewRun n;
  n.procedure_name = "six-position";
  n.procedure_text = "{}";
  const std::int64_t run = runs.create_run(n);
  runs.set_run_status(run, "running");
  EXPECT_EQ(runs.load_run(run).summary.status, "interrupted");
  EXPECT_EQ(runs.list_runs().front().status, "interrupted");
  EXPECT_EQ(runs.run_status(run), "running") << "the row itself is left as it is";
  {
    const RunLock driver(db, run);
    EXPECT_EQ(runs.load_run(run).summary.status, "running");
    EXPECT_EQ(runs.list_runs().front().status, "running");
  }
  runs.set_run_status(run, "completed");
  EXPECT_EQ(runs.load_run(run).summary.status, "completed") << "ended runs are what they say";
}

}  // namespace
}  // namespace calstand::store

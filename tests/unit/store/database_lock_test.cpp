#include "store/database_lock.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <optional>

namespace {

using calstand::store::DatabaseBusy;
using calstand::store::DatabaseLock;
using Mode = DatabaseLock::Mode;

std::string fresh_db(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("calstand-lock-" + std::to_string(::getpid()) + "-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return (dir / "station.db").string();
}

// flock() locks belong to open file descriptions: a second lock in the same process conflicts
// with the first just as another process's would (each DatabaseLock opens the file anew).
TEST(DatabaseLock, AnExclusiveHolderKeepsEveryoneElseOutAndIsNamed) {
  const std::string db = fresh_db("exclusive");
  DatabaseLock daemon(db, Mode::kExclusive, "calstandd pid 42 listening on 127.0.0.1:8765");
  try {
    DatabaseLock run(db, Mode::kShared, "calstand run");
    FAIL() << "a shared lock was granted beside an exclusive one";
  } catch (const DatabaseBusy& e) {
    EXPECT_NE(std::string(e.what()).find("calstandd pid 42 listening on 127.0.0.1:8765"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("calstand submit"), std::string::npos) << e.what();
  }
  EXPECT_THROW(DatabaseLock(db, Mode::kExclusive, "second daemon"), DatabaseBusy);
}

TEST(DatabaseLock, SharedHoldersCoexistButKeepADaemonOut) {
  const std::string db = fresh_db("shared");
  DatabaseLock first(db, Mode::kShared, "calstand run");
  EXPECT_NO_THROW(DatabaseLock(db, Mode::kShared, "calstand run"));
  try {
    DatabaseLock daemon(db, Mode::kExclusive, "calstandd");
    FAIL() << "an exclusive lock was granted beside a shared one";
  } catch (const DatabaseBusy& e) {
    EXPECT_NE(std::string(e.what()).find("foreground `calstand run`"), std::string::npos)
        << e.what();
  }
}

TEST(DatabaseLock, IsReleasedWhenTheHolderGoesAwayOrDies) {
  const std::string db = fresh_db("release");
  { DatabaseLock daemon(db, Mode::kExclusive, "calstandd"); }
  EXPECT_NO_THROW(DatabaseLock(db, Mode::kExclusive, "calstandd again"));

  // A holder killed with SIGKILL leaves no stale lock.
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    DatabaseLock held(db, Mode::kExclusive, "child");
    const char byte = 1;
    [[maybe_unused]] const auto n = ::write(ready[1], &byte, 1);
    ::pause();
    ::_exit(0);
  }
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  EXPECT_THROW(DatabaseLock(db, Mode::kShared, "calstand run"), DatabaseBusy);
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  EXPECT_NO_THROW(DatabaseLock(db, Mode::kShared, "calstand run"));
  ::close(ready[0]);
  ::close(ready[1]);
}

}  // namespace

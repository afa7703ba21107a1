// calstandd under systemd, with a datagram socket standing in for it: READY=1 once it serves,
// STATUS= lines, WATCHDOG=1 from the run thread (a hung run thread stops them), STOPPING=1 on
// SIGTERM; and the upgrade on start: an older database backed up and migrated with a log
// line, a newer one refused by name.
#include <SQLiteCpp/Database.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <string>

#include "../support/notify_peer.hpp"
#include "../support/older_database.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/run_service.hpp"
#include "daemon/service/service_heartbeat.hpp"
#include "daemon/service/systemd_notify.hpp"
#include "daemon_test_support.hpp"
#include "procedures/procedure.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"

namespace calstand::testing::systemd_it {

using std::chrono::milliseconds;

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

int schema_of(const std::string& path) {
  SQLite::Database db(path, SQLite::OPEN_READONLY);
  return db.execAndGet("PRAGMA user_version").getInt();
}

bool has_status(const NotifyMessage& m, const std::string& prefix) {
  return m.count("STATUS") != 0 && m.at("STATUS").rfind(prefix, 0) == 0;
}

TEST(DaemonSystemd, SaysReadyStatusAndStoppingAndPingsTheWatchdog) {
  const std::string dir = fresh_dir("systemd-notify");
  DatagramPeer systemd(dir + "/notify.sock");
  DaemonProcess d(dir + "/station.db", dir + "/calstandd.log", "127.0.0.1:0", {},
                  {{"NOTIFY_SOCKET", systemd.address()}, {"WATCHDOG_USEC", "1000000"}});
  ASSERT_GT(d.port(), 0) << slurp(dir + "/calstandd.log");
  // READY comes once it serves, with the station's status.
  const auto ready = systemd.wait_for([](const NotifyMessage& m) { return m.count("READY"); },
                                      milliseconds(20000));
  ASSERT_TRUE(ready) << slurp(dir + "/calstandd.log");
  EXPECT_EQ(ready->at("READY"), "1");
  EXPECT_EQ(ready->at("STATUS"), "idle");
  // Between runs the run thread pings at least every half second (WatchdogSec=1).
  int pings = 0;
  const auto got = systemd.collect(milliseconds(2000));
  for (const auto& [at, datagram] : got)
    pings += static_cast<int>(parse_notify_message(datagram).count("WATCHDOG"));
  EXPECT_GE(pings, 3) << "2 s idle at a 1 s watchdog";
  // A run shows in the status, by step.
  ApiClient api(d.port());
  const std::int64_t run = api.submit("six-position", {{"capture_s", 300}});
  ASSERT_GT(run, 0);
  const auto running = systemd.wait_for(
      [&](const NotifyMessage& m) {
        return has_status(m, "running run " + std::to_string(run) + " step ");
      },
      milliseconds(60000));
  ASSERT_TRUE(running) << slurp(dir + "/calstandd.log");
  EXPECT_NE(running->at("STATUS").find("/"), std::string::npos) << running->at("STATUS");
  // SIGTERM: STOPPING first, then the checkpoint and a clean exit.
  ::kill(d.pid(), SIGTERM);
  const auto stopping = systemd.wait_for([](const NotifyMessage& m) { return m.count("STOPPING"); },
                                         milliseconds(30000));
  ASSERT_TRUE(stopping);
  EXPECT_EQ(stopping->at("STOPPING"), "1");
  EXPECT_TRUE(has_status(*stopping, "stopping")) << stopping->at("STATUS");
  EXPECT_EQ(d.signal_and_wait(0), 0) << slurp(dir + "/calstandd.log");
}

// The engine hangs in its tick (here: in the heartbeat call the run thread makes each tick,
// blocked on a gate): the pings stop, while the other threads still answer; when the tick goes
// on, so do the pings. No other thread pings for it.
TEST(DaemonSystemd, AHungRunThreadStopsTheWatchdogPings) {
  const std::string dir = fresh_dir("systemd-hang");
  DatagramPeer systemd(dir + "/notify.sock");
  const daemon::service::SystemdNotifier notifier(systemd.address(),
                                                  std::chrono::microseconds(400000));
  daemon::service::EventHub hub(256);
  daemon::service::RunService service({sim::load_station_or_default(""), dir + "/station.db",
                                       daemon::service::RecoveryPolicy::kAuto},
                                      hub);
  auto heartbeat = std::make_shared<daemon::service::ServiceHeartbeat>(
      notifier, [&service] { return service.snapshot(); });
  std::mutex gate_mutex;
  std::condition_variable gate;
  bool hang = false;
  std::atomic<bool> hung{false};
  service.set_heartbeat(
      [&, heartbeat] {
        std::unique_lock lock(gate_mutex);
        if (hang) {
          hung = true;
          gate.wait(lock, [&] { return !hang; });
          hung = false;
        }
        lock.unlock();
        heartbeat->beat();
      },
      milliseconds(100));
  service.start();
  const auto procedure = procedures::load_procedure("six-position");
  const std::int64_t run = service.submit(procedure, {{"capture_s", 300}}, "tester");
  ASSERT_TRUE(systemd.wait_for(
      [&](const NotifyMessage& m) {
        return has_status(m, "running run " + std::to_string(run) + " step ");
      },
      milliseconds(60000)));
  {
    std::lock_guard lock(gate_mutex);
    hang = true;
  }
  ASSERT_TRUE(wait_until([&] { return hung.load(); }, milliseconds(20000)));
  systemd.collect(milliseconds(50));  // what was sent before the hang
  // Five watchdog periods without a ping, while the service still answers other threads.
  const auto quiet = systemd.collect(milliseconds(2000));
  int pings = 0;
  for (const auto& [at, datagram] : quiet)
    pings += static_cast<int>(parse_notify_message(datagram).count("WATCHDOG"));
  EXPECT_EQ(pings, 0) << "pings while the run thread hangs";
  EXPECT_EQ(service.snapshot().run, run);
  {
    std::lock_guard lock(gate_mutex);
    hang = false;
  }
  gate.notify_all();
  EXPECT_TRUE(systemd.wait_for([](const NotifyMessage& m) { return m.count("WATCHDOG"); },
                               milliseconds(5000)))
      << "the pings come back with the run thread";
  service.stop("test over");
}

TEST(DaemonUpgrade, AnOlderDatabaseIsBackedUpAndMigratedOnStartWithALogLine) {
  const std::string dir = fresh_dir("upgrade");
  const std::string db = dir + "/station.db";
  const int older = store::latest_schema_version() - 1;
  make_database_at_version(db, std::string(CALSTAND_SOURCE_DIR) + "/store/schema.sql", older);
  const std::string log = dir + "/calstandd.log";
  {
    DaemonProcess d(db, log);
    ASSERT_GT(d.port(), 0) << slurp(log);
    EXPECT_EQ(d.signal_and_wait(SIGTERM), 0) << slurp(log);
  }
  const std::string backup = db + ".schema" + std::to_string(older) + ".bak";
  ASSERT_TRUE(std::filesystem::exists(backup)) << slurp(log);
  EXPECT_EQ(schema_of(backup), older);
  EXPECT_EQ(schema_of(db), store::latest_schema_version());
  const std::string said = slurp(log);
  EXPECT_NE(
      said.find("migrated from schema " + std::to_string(older) + " to " +
                std::to_string(store::latest_schema_version()) + "; the copy as it was: " + backup),
      std::string::npos)
      << said;
  // The next start finds nothing to do: no second backup.
  {
    DaemonProcess d(db, log);
    ASSERT_GT(d.port(), 0);
    EXPECT_EQ(d.signal_and_wait(SIGTERM), 0);
  }
  EXPECT_FALSE(std::filesystem::exists(db + ".schema" + std::to_string(older) + ".1.bak"));
}

TEST(DaemonUpgrade, ADatabaseNewerThanTheDaemonIsRefusedByName) {
  const std::string dir = fresh_dir("downgrade");
  const std::string db = dir + "/station.db";
  const int newer = store::latest_schema_version() + 1;
  {
    store::Database database(db);
    database.sql().exec("PRAGMA user_version = " + std::to_string(newer));
  }
  const std::string command = std::string(CALSTANDD_BIN) + " --db " + db +
                              " --listen 127.0.0.1:0 >/dev/null 2>" + dir + "/err.txt";
  const int status = std::system(command.c_str());
  EXPECT_EQ(WEXITSTATUS(status), 1);
  const std::string said = slurp(dir + "/err.txt");
  EXPECT_NE(said.find(db), std::string::npos) << said;
  EXPECT_NE(said.find("schema version " + std::to_string(newer) + " is newer than this calstand's"),
            std::string::npos)
      << said;
  EXPECT_NE(said.find("downgrade is refused"), std::string::npos) << said;
  EXPECT_EQ(schema_of(db), newer);
}

}  // namespace calstand::testing::systemd_it

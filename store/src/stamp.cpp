#include "store/stamp.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>

#include <chrono>

namespace calstand::store {

std::string utc_now_iso8601() {
  using namespace std::chrono;
  const auto now = time_point_cast<milliseconds>(system_clock::now());
  const auto secs = time_point_cast<seconds>(now);
  const auto ms = (now - secs).count();
  return fmt::format("{:%Y-%m-%dT%H:%M:%S}.{:03d}Z", fmt::gmtime(system_clock::to_time_t(secs)),
                     ms);
}

}  // namespace calstand::store

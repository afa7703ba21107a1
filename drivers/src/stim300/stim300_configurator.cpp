// The STIM300 dialogue: N, I, C while the unit streams, then what it streams against the
// station file (stim300_configurator.hpp).
#include "drivers/stim300_configurator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

#include "drivers/device_dialogue.hpp"
#include "drivers/stim300_decoder.hpp"

namespace calstand::drivers::stim300 {
namespace {

using namespace std::chrono_literals;

constexpr auto kStim300ReplyTimeout = 500ms;
constexpr int kStim300Attempts = 3;
// Fewer datagrams than this in the watch do not make a rate.
constexpr std::uint64_t kStim300MinObserved = 8;

std::vector<std::uint8_t> stim300_ask(ByteTransport& link, const char* command, ReplyKind kind,
                                      const std::string& what) {
  const std::string_view text(command);
  const std::vector<std::uint8_t> request(text.begin(), text.end());
  const ReplyFinder finder =
      [kind](std::span<const std::uint8_t> received) -> std::optional<std::vector<std::uint8_t>> {
    const auto scan = find_reply(received, kind);
    if (scan.result != ScanResult::kFound) return std::nullopt;
    const auto first = received.begin() + static_cast<std::ptrdiff_t>(scan.offset);
    return std::vector<std::uint8_t>(first, first + static_cast<std::ptrdiff_t>(scan.size));
  };
  return request_reply(link, request, finder, kStim300ReplyTimeout, kStim300Attempts, what);
}

std::string stim300_rates_text() {
  std::string out;
  const auto rates = sample_rates_hz();
  for (std::size_t i = 0; i < rates.size(); ++i) {
    out += fmt::format("{}{:g}", i == 0 ? "" : (i + 1 == rates.size() ? " or " : ", "), rates[i]);
  }
  return out + " Hz";
}

// What the unit streams, as watched for a while.
struct Stim300Observed {
  std::optional<std::uint8_t> datagram;
  std::uint64_t datagrams = 0;
  std::uint64_t terminated = 0;
  std::optional<double> rate_hz;  // counter steps over host time, after the backlog
};

/// The unit's rate nearest to a measured one. The rates differ by factors of 2, so a measured
/// rate within a factor of sqrt(2) names one; a host under load delivers the stream in bursts,
/// which moves a rate measured over half a second by tens of percent (CI saw 316 Hz for 250).
double stim300_nearest_rate(double measured_hz) {
  const auto rates = sample_rates_hz();
  return *std::min_element(rates.begin(), rates.end(), [measured_hz](double a, double b) {
    return std::abs(std::log(a / measured_hz)) < std::abs(std::log(b / measured_hz));
  });
}

/// Least-squares slope of counter steps over host seconds: every chunk's arrival counts, so one
/// late or early chunk moves the rate less than it moves a two-point difference.
std::optional<double> counter_rate_per_s(const std::vector<std::pair<double, double>>& points) {
  if (points.size() < 3) return std::nullopt;
  double mean_t = 0.0, mean_n = 0.0;
  for (const auto& [t, n] : points) {
    mean_t += t;
    mean_n += n;
  }
  mean_t /= static_cast<double>(points.size());
  mean_n /= static_cast<double>(points.size());
  double stt = 0.0, stn = 0.0;
  for (const auto& [t, n] : points) {
    stt += (t - mean_t) * (t - mean_t);
    stn += (t - mean_t) * (n - mean_n);
  }
  if (stt <= 0.0) return std::nullopt;
  return stn / stt;
}

/// What the unit streams over `observe` of wall time; its rate in station time, the wall's
/// `time_scale` times slower (a unit rehearsed by sim-station at K times the wall).
Stim300Observed stim300_observe(ByteTransport& link, std::chrono::milliseconds observe,
                                double time_scale) {
  using Clock = std::chrono::steady_clock;
  Stim300Decoder decoder(Stim300Options{}, 2000.0);  // any identifier, either termination
  std::array<std::uint8_t, 4096> chunk{};
  std::vector<core::ImuSample> samples;
  bool backlog = true;  // the first chunk holds what queued during the dialogue
  const auto start = Clock::now();
  const auto deadline = start + observe;
  // (host seconds since the watch began, counter unwrapped from the first timed datagram)
  std::vector<std::pair<double, double>> arrivals;
  std::uint32_t first_counter = 0;
  while (Clock::now() < deadline) {
    const IoResult r = link.read(chunk, 20ms);
    if (!r.ok()) throw DeviceConfigError(r.error);
    if (r.bytes == 0) continue;
    const auto now = Clock::now();
    samples.clear();
    decoder.feed(std::span(chunk).first(r.bytes), samples);
    if (samples.empty()) continue;
    // Timing starts after the backlog: its datagrams arrived together, not at the rate.
    if (backlog) {
      backlog = false;
      first_counter = samples.back().sequence;
      continue;
    }
    arrivals.emplace_back(std::chrono::duration<double>(now - start).count(),
                          static_cast<double>(samples.back().sequence - first_counter));
  }
  Stim300Observed o;
  o.datagram = decoder.datagram_id();
  o.datagrams = decoder.stats().frames;
  o.terminated = decoder.stats().terminated_datagrams;
  if (!arrivals.empty() && arrivals.back().second >= kStim300MinObserved) {
    const auto per_wall_s = counter_rate_per_s(arrivals);
    if (per_wall_s && *per_wall_s > 0.0) o.rate_hz = *per_wall_s / time_scale;
  }
  return o;
}

}  // namespace

Stim300Configurator::Stim300Configurator(WireFormatSettings settings, Stim300Options options,
                                         std::chrono::milliseconds observe)
    : settings_(std::move(settings)), options_(options), observe_(observe) {}

UnitIdentity Stim300Configurator::configure(ByteTransport& link) {
  if (!is_sample_rate(settings_.sample_rate_hz)) {
    throw DeviceConfigError(fmt::format("STIM300 samples at {}, not {:g} Hz", stim300_rates_text(),
                                        settings_.sample_rate_hz));
  }
  UnitIdentity identity;
  const auto part =
      digits_of(stim300_ask(link, kCommandPartNumber, kPartNumber, "N (part number)"));
  identity.model = "STIM300 " + part;
  identity.serial =
      digits_of(stim300_ask(link, kCommandSerialNumber, kSerialNumber, "I (serial number)"));
  // The configuration is read as the sheet's dialogue has it, but its bytes are not
  // interpreted (docs/protocols.md, "open details"): what the unit streams is checked instead.
  stim300_ask(link, kCommandConfiguration, kConfiguration, "C (configuration)");

  const auto seen = stim300_observe(link, observe_, settings_.time_scale);
  const std::string unit = fmt::format("STIM300 {} (serial {})", part, identity.serial);
  if (!seen.datagram) {
    throw DeviceConfigError(fmt::format(
        "{}: answered N, I, C but sent no normal-mode datagram this driver reads (0x90..0x94, "
        "0xA5..0xA7) within {} ms",
        unit, observe_.count()));
  }
  const bool terminated = seen.terminated * 2 > seen.datagrams;
  const std::string streams = fmt::format(
      "{} streams datagram {} {} CR LF at {}", unit, datagram_name(*seen.datagram),
      terminated ? "with" : "without",
      seen.rate_hz ? fmt::format("about {:.0f} Hz", *seen.rate_hz) : "an unmeasured rate");
  std::vector<std::string> differ;
  const bool rate_differs =
      !seen.rate_hz || stim300_nearest_rate(*seen.rate_hz) != settings_.sample_rate_hz;
  if (options_.rate_check && rate_differs) {
    differ.push_back(fmt::format("sample_rate_hz {:g}", settings_.sample_rate_hz));
  }
  if (options_.datagram && *options_.datagram != *seen.datagram) {
    differ.push_back(fmt::format("datagram {}", datagram_name(*options_.datagram)));
  }
  if (options_.termination && *options_.termination != terminated) {
    differ.push_back(fmt::format("termination {}", *options_.termination));
  }
  if (!differ.empty()) {
    std::string asks;
    for (const auto& d : differ) asks += (asks.empty() ? "" : ", ") + d;
    throw DeviceConfigError(
        fmt::format("{}; the station file ({}) asks {} (the unit is set up in its service mode)",
                    streams, settings_.where, asks));
  }
  return identity;
}

}  // namespace calstand::drivers::stim300

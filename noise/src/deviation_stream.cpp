// Overlapping Allan, Hadamard and modified Allan variances of a streamed rate record at octave
// averaging factors, in memory that does not grow with the record (see deviation_stream.hpp).
#include "noise/deviation_stream.hpp"

#include <fmt/format.h>

#include <Eigen/Core>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <utility>

#include "core/error.hpp"
#include "noise/edf.hpp"
#include "noise/noise_identification.hpp"

namespace calstand::solver {
namespace {

// Samples whose mean is taken out of the rate before the phase is summed.
constexpr std::size_t kMeanSamples = std::size_t{1} << 16U;
// Phase points a full-rate buffer takes between two shifts.
constexpr std::size_t kLevelZeroBlock = std::size_t{1} << 16U;

bool is_power_of_two(std::size_t v) { return v != 0 && (v & (v - 1)) == 0; }

// Sum of squared second differences x[i + 2m] - 2 x[i + m] + x[i], i in [begin, end).
double stream_second_sum(const double* x, std::size_t m, std::size_t begin, std::size_t end) {
  const auto len = static_cast<Eigen::Index>(end - begin);
  const Eigen::Map<const Eigen::ArrayXd> a(x + begin, len);
  const Eigen::Map<const Eigen::ArrayXd> b(x + begin + m, len);
  const Eigen::Map<const Eigen::ArrayXd> c(x + begin + 2 * m, len);
  return (c - 2.0 * b + a).square().sum();
}

// Sum of squared third differences x[i + 3m] - 3 x[i + 2m] + 3 x[i + m] - x[i], i in
// [begin, end).
double stream_third_sum(const double* x, std::size_t m, std::size_t begin, std::size_t end) {
  const auto len = static_cast<Eigen::Index>(end - begin);
  const Eigen::Map<const Eigen::ArrayXd> a(x + begin, len);
  const Eigen::Map<const Eigen::ArrayXd> b(x + begin + m, len);
  const Eigen::Map<const Eigen::ArrayXd> c(x + begin + 2 * m, len);
  const Eigen::Map<const Eigen::ArrayXd> d(x + begin + 3 * m, len);
  return (d - 3.0 * c + 3.0 * b - a).square().sum();
}

// One phase series: every phase point (level 0), or every D-th point, or the means of blocks of
// D points (D = 2^level), with the difference sums of its lags. Points are kept in a buffer of
// the last `history` points plus a block of new ones, relative to `anchor`.
struct PhaseSeries {
  enum class Feed { kSampled, kAveraged };
  std::size_t level = 0;
  std::size_t exact_max_m = 0;
  bool allan = false, hadamard = false, modified = false;
  bool feeds_sampled = false, feeds_averaged = false;  // children it makes
  std::vector<std::size_t> lags;                       // in points of this series
  std::size_t history = 0;
  std::vector<double> buf;
  std::size_t filled = 0;     // points in buf
  std::size_t processed = 0;  // buf[0, processed) have had their sums taken
  std::size_t count = 0;      // points pushed in all
  long double anchor = 0.0L;
  // The last point pushed, previous_origin + previous_rel (the averaged child's pairs).
  double previous_rel = 0.0;
  long double previous_origin = 0.0L;
  // Per lag: sums of squared differences and their counts; the modified estimator's window.
  std::vector<double> allan_sum, hadamard_sum, modified_sum, window;
  std::vector<std::size_t> allan_terms, hadamard_terms, modified_terms;
  std::unique_ptr<PhaseSeries> sampled_child, averaged_child;
  std::vector<double> child_scratch;

  PhaseSeries(std::size_t level_, std::size_t exact_max_m_, bool a, bool h, bool mod, bool fs,
              bool fa)
      : level(level_),
        exact_max_m(exact_max_m_),
        allan(a),
        hadamard(h),
        modified(mod),
        feeds_sampled(fs),
        feeds_averaged(fa) {
    if (level == 0) {
      for (std::size_t m = 1; m <= exact_max_m; m *= 2) lags.push_back(m);
    } else {
      lags.push_back(exact_max_m);
    }
    history = (hadamard || modified ? 3 : 2) * exact_max_m;
    const std::size_t block = level == 0 ? std::max(kLevelZeroBlock, history) : history / 2;
    buf.resize(history + std::max<std::size_t>(block, 64));
    const std::size_t n = lags.size();
    allan_sum.assign(n, 0.0);
    hadamard_sum.assign(n, 0.0);
    modified_sum.assign(n, 0.0);
    window.assign(n, 0.0);
    allan_terms.assign(n, 0);
    hadamard_terms.assign(n, 0);
    modified_terms.assign(n, 0);
  }

  // Takes the sums of the points not yet processed.
  void process() {
    const std::size_t base = count - filled;  // index of buf[0] in the series
    const double* x = buf.data();
    // The Allan and Hadamard sums in slices of 2048 ends, every lag per slice: the slice's
    // newest points stay in L1 across the lags (as allan.cpp's blocked pass).
    constexpr std::size_t kSlice = 2048;
    for (std::size_t begin = processed; begin < filled; begin += kSlice) {
      const std::size_t end = std::min(begin + kSlice, filled);
      for (std::size_t k = 0; k < lags.size(); ++k) {
        const std::size_t m = lags[k];
        // First buffer index whose point ends a difference of span 2m (3m): base >= 2m (3m)
        // once the buffer has shifted, as the history holds that many points.
        const std::size_t lo2 = std::max(begin, base >= 2 * m ? 0 : 2 * m - base);
        const std::size_t lo3 = std::max(begin, base >= 3 * m ? 0 : 3 * m - base);
        if (allan && lo2 < end) {
          allan_sum[k] += stream_second_sum(x, m, lo2 - 2 * m, end - 2 * m);
          allan_terms[k] += end - lo2;
        }
        if (hadamard && lo3 < end) {
          hadamard_sum[k] += stream_third_sum(x, m, lo3 - 3 * m, end - 3 * m);
          hadamard_terms[k] += end - lo3;
        }
      }
    }
    for (std::size_t k = 0; k < lags.size(); ++k) {
      const std::size_t m = lags[k];
      const std::size_t lo2 = std::max(processed, base >= 2 * m ? 0 : 2 * m - base);
      if (modified) {
        // As allan.cpp's modified_sum: a window of m second differences, moved by one.
        const auto d = [&](std::size_t e) { return x[e] - 2.0 * x[e - m] + x[e - 2 * m]; };
        double w = window[k];
        double s = modified_sum[k];
        std::size_t t = modified_terms[k];
        for (std::size_t e = lo2; e < filled; ++e) {
          const std::size_t i = base + e - 2 * m;  // index of the difference's first point
          if (i < m) {
            w += d(e);
            if (i + 1 == m) {
              s += w * w;
              ++t;
            }
          } else {
            w += d(e) - d(e - m);
            s += w * w;
            ++t;
          }
        }
        window[k] = w;
        modified_sum[k] = s;
        modified_terms[k] = t;
      }
    }
    processed = filled;
  }

  // Keeps the last `history` points, re-centred on the newest.
  void shift() {
    const std::size_t keep = std::min(history, filled);
    const double centre = buf[filled - 1];
    std::memmove(buf.data(), buf.data() + (filled - keep), keep * sizeof(double));
    for (std::size_t i = 0; i < keep; ++i) buf[i] -= centre;
    anchor += centre;
    filled = keep;
    processed = keep;
  }

  std::unique_ptr<PhaseSeries> make_child(Feed feed) const {
    const bool sampled = feed == Feed::kSampled;
    return std::make_unique<PhaseSeries>(level + 1, exact_max_m, sampled && allan,
                                         sampled && hadamard, !sampled && modified, sampled,
                                         !sampled);
  }

  // The child's points made of this series' points [from, to) (series indices), each
  // origin + rel[j - from]. A pair split between two pushes of the same origin gives the same
  // double as within one; one whose points have different origins (only where the root's
  // origin moves, at fixed indices) is re-based on the new origin.
  void feed_children(const double* rel, std::size_t from, std::size_t to, long double origin) {
    if (to <= from) return;
    // The first index of [from, to) of each parity, relative to `from`.
    const std::size_t first_even = from % 2;
    const std::size_t first_odd = 1 - from % 2;
    const std::size_t n = to - from;
    if (sampled_child) {
      child_scratch.resize((n - first_even + 1) / 2);
      for (std::size_t j = first_even, c = 0; j < n; j += 2, ++c) child_scratch[c] = rel[j];
      sampled_child->push(child_scratch.data(), child_scratch.size(), origin);
    }
    if (averaged_child) {
      child_scratch.resize(n > first_odd ? (n - first_odd + 1) / 2 : 0);
      std::size_t c = 0, j = first_odd;
      if (j == 0 && n > 0) {
        const double before = previous_origin == origin
                                  ? previous_rel
                                  : static_cast<double>(previous_origin - origin) + previous_rel;
        child_scratch[c++] = 0.5 * (before + rel[0]);
        j += 2;
      }
      for (; j < n; j += 2, ++c) child_scratch[c] = 0.5 * (rel[j - 1] + rel[j]);
      averaged_child->push(child_scratch.data(), child_scratch.size(), origin);
    }
  }

  // Appends points origin + rel[0 .. n).
  void push(const double* rel, std::size_t n, long double origin) {
    std::size_t i = 0;
    while (i < n) {
      if (filled == buf.size()) {
        process();
        shift();
      }
      const std::size_t take = std::min(n - i, buf.size() - filled);
      const double offset = static_cast<double>(origin - anchor);
      for (std::size_t k = 0; k < take; ++k) buf[filled + k] = rel[i + k] + offset;
      feed_children(rel + i, count, count + take, origin);
      previous_rel = rel[i + take - 1];
      previous_origin = origin;
      filled += take;
      count += take;
      // A child is made once this series has 2 exact_max_m points (its scale needs 2
      // exact_max_m + 1 of its own, twice as many of these); the buffer has not shifted yet
      // (it holds more), so its first points are made from the buffer.
      if (count >= 2 * exact_max_m && count == filled &&
          ((feeds_sampled && !sampled_child) || (feeds_averaged && !averaged_child))) {
        if (feeds_sampled) sampled_child = make_child(Feed::kSampled);
        if (feeds_averaged) averaged_child = make_child(Feed::kAveraged);
        const std::vector<double> all(buf.begin(), buf.begin() + static_cast<long>(filled));
        feed_children(all.data(), 0, filled, anchor);
      }
      i += take;
    }
  }

  void process_all() {
    process();
    if (sampled_child) sampled_child->process_all();
    if (averaged_child) averaged_child->process_all();
  }
};

}  // namespace

struct DeviationStream::State {
  std::vector<AllanKind> kinds;
  std::size_t exact_max_m = 0;
  std::size_t samples = 0;
  std::vector<double> pending;  // the first samples, until their mean is known
  bool mean_known = false;
  double mean = 0.0;
  long double phase_origin = 0.0L;  // the phase is phase_origin + phase_rel
  double phase_rel = 0.0;
  std::vector<double> scratch;
  std::unique_ptr<PhaseSeries> root;
  // The lag-1 noise identification's sums of the phase decimated by m = 2^j, j = 0, 1, ...: a
  // level is made when point 2^j arrives (its first point is phase[0] = 0).
  int lag1_dmax = 2;
  std::vector<Lag1Accumulator> lag1;

  bool has(AllanKind k) const { return std::find(kinds.begin(), kinds.end(), k) != kinds.end(); }

  // Phase points first_index, first_index + 1, ... (first_index >= 1), origin + rel[k], to
  // the octave factors that take them: point i is every 2^j-th point for 2^j dividing i. Each
  // factor's points are taken in order, so the sums do not depend on the blocks.
  void identify_points(const double* rel, std::size_t n, std::size_t first_index,
                       long double origin) {
    const auto base = static_cast<double>(origin);
    const std::size_t end = first_index + n;
    for (std::size_t j = 0;; ++j) {
      const std::size_t step = std::size_t{1} << j;
      const std::size_t first = (first_index + step - 1) / step * step;
      if (first >= end) break;  // nor any multiple of 2^(j+1)
      if (j == lag1.size()) {
        // Point 2^j, never reached before: the factor's first point is phase[0] = 0.
        lag1.emplace_back(lag1_dmax);
        lag1.back().push(0.0);
      }
      lag1[j].push(rel + (first - first_index), (end - 1 - first) / step + 1, step, base);
      if (j == 63) break;
    }
  }

  // The phase is summed in double from an origin that moves (in long double) every
  // kOriginPoints points of the record, at fixed indices: the sums stay as small as the phase's
  // excursion over those points, and the values do not depend on the blocks pushed.
  void feed(std::span<const double> rate) {
    constexpr std::size_t kOriginPoints = 4096;
    std::size_t i = 0;
    if (root->count == 0) {
      const double zero = 0.0;  // phase[0] = 0, as phase_from_rate()
      root->push(&zero, 1, 0.0L);
    }
    while (i < rate.size()) {
      // Point root->count is the next; its segment ends at the next multiple of kOriginPoints.
      const std::size_t next = root->count;
      const std::size_t take = std::min(rate.size() - i, kOriginPoints - next % kOriginPoints);
      if (next % kOriginPoints == 0) {
        phase_origin += static_cast<long double>(phase_rel);
        phase_rel = 0.0;
      }
      scratch.resize(take);
      double p = phase_rel;
      for (std::size_t k = 0; k < take; ++k) {
        p += rate[i + k] - mean;
        scratch[k] = p;
      }
      phase_rel = p;
      identify_points(scratch.data(), take, root->count, phase_origin);
      root->push(scratch.data(), take, phase_origin);
      i += take;
    }
  }

  void fix_mean() {
    if (mean_known) return;
    double sum = 0.0;
    for (const double r : pending) sum += r;
    mean = sum / static_cast<double>(std::max<std::size_t>(pending.size(), 1));
    mean_known = true;
    std::vector<double> first;
    first.swap(pending);
    for (std::size_t i = 0; i < first.size(); i += kLevelZeroBlock) {
      feed(std::span<const double>(first).subspan(i, std::min(kLevelZeroBlock, first.size() - i)));
    }
  }
};

DeviationStream::DeviationStream(std::vector<AllanKind> kinds, std::size_t exact_max_m)
    : state_(std::make_unique<State>()) {
  if (kinds.empty()) throw core::InputError("kinds", "no deviation to accumulate");
  for (const AllanKind k : kinds) {
    if (k == AllanKind::kHadamardNonOverlapping) {
      throw core::InputError("kinds",
                             "hdev (non-overlapping) is not streamed; adev, ohdev and mdev are");
    }
  }
  if (!is_power_of_two(exact_max_m) || exact_max_m < 4) {
    throw core::InputError("exact_max_m",
                           fmt::format("must be a power of two >= 4, got {}", exact_max_m));
  }
  State& s = *state_;
  s.kinds = std::move(kinds);
  s.exact_max_m = exact_max_m;
  const bool a = s.has(AllanKind::kAllan), h = s.has(AllanKind::kHadamard),
             mod = s.has(AllanKind::kModified);
  s.root = std::make_unique<PhaseSeries>(0, exact_max_m, a, h, mod, a || h, mod);
  s.lag1_dmax = h ? difference_order(AllanKind::kHadamard) : difference_order(AllanKind::kAllan);
}

DeviationStream::~DeviationStream() = default;
DeviationStream::DeviationStream(DeviationStream&&) noexcept = default;
DeviationStream& DeviationStream::operator=(DeviationStream&&) noexcept = default;

std::size_t DeviationStream::samples() const { return state_->samples; }

void DeviationStream::push(std::span<const double> rate) {
  State& s = *state_;
  for (std::size_t i = 0; i < rate.size(); ++i) {
    if (!std::isfinite(rate[i])) {
      throw core::InputError("data",
                             fmt::format("sample {} is not finite ({})", s.samples + i, rate[i]));
    }
  }
  s.samples += rate.size();
  if (!s.mean_known) {
    const std::size_t take = std::min(rate.size(), kMeanSamples - s.pending.size());
    s.pending.insert(s.pending.end(), rate.begin(), rate.begin() + static_cast<long>(take));
    rate = rate.subspan(take);
    if (s.pending.size() < kMeanSamples) return;
    s.fix_mean();
  }
  for (std::size_t i = 0; i < rate.size(); i += kLevelZeroBlock) {
    s.feed(rate.subspan(i, std::min(kLevelZeroBlock, rate.size() - i)));
  }
}

AllanResult DeviationStream::result(double sample_rate_hz, const AllanOptions& options) {
  options.validate();
  State& s = *state_;
  if (!std::isfinite(sample_rate_hz) || sample_rate_hz <= 0.0) {
    throw core::InputError("sample_rate_hz",
                           fmt::format("must be positive and finite, got {}", sample_rate_hz));
  }
  if (options.taus.spacing != TauSpacing::kOctave) {
    throw core::InputError("taus",
                           "a streamed record gives the octave averaging times (1, 2, 4, ... "
                           "samples) only");
  }
  if (!s.has(options.kind)) {
    throw core::InputError("kind", fmt::format("{} was not accumulated", to_string(options.kind)));
  }
  const std::size_t min_samples = options.kind == AllanKind::kAllan ? 2 : 3;
  if (s.samples < min_samples) {
    throw core::InputError("data", fmt::format("{} samples; {} needs at least {}", s.samples,
                                               to_string(options.kind), min_samples));
  }
  s.fix_mean();
  s.root->process_all();
  const std::vector<std::size_t> ms =
      averaging_factors(options.taus, s.samples, sample_rate_hz, options.kind);
  std::vector<double> var;
  std::vector<std::size_t> terms;
  for (const std::size_t m : ms) {
    const PhaseSeries* series = s.root.get();
    std::size_t lag = 0;
    if (m <= s.exact_max_m) {
      while ((std::size_t{1} << lag) < m) ++lag;
    } else {
      for (std::size_t d = m / s.exact_max_m; d > 1 && series; d /= 2) {
        series =
            (options.kind == AllanKind::kModified ? series->averaged_child : series->sampled_child)
                .get();
      }
    }
    std::size_t t = 0;
    double sum = 0.0;
    if (series) {
      switch (options.kind) {
        case AllanKind::kAllan:
          t = series->allan_terms[lag];
          sum = series->allan_sum[lag];
          break;
        case AllanKind::kHadamard:
          t = series->hadamard_terms[lag];
          sum = series->hadamard_sum[lag];
          break;
        case AllanKind::kModified:
          t = series->modified_terms[lag];
          sum = series->modified_sum[lag];
          break;
        case AllanKind::kHadamardNonOverlapping:
          break;
      }
    }
    if (t == 0) {
      throw std::logic_error(fmt::format("streamed {} has no term at m = {} of {} samples",
                                         to_string(options.kind), m, s.samples));
    }
    const double md = static_cast<double>(m);
    const double td = static_cast<double>(t);
    double v = 0.0;
    if (options.kind == AllanKind::kAllan) {
      v = sum / (2.0 * md * md * td);
    } else if (options.kind == AllanKind::kHadamard) {
      v = sum / (6.0 * md * md * td);
    } else {
      // The window of a strided level sums means of D points: D times the phase sums.
      const double dd = m > s.exact_max_m ? md / static_cast<double>(s.exact_max_m) : 1.0;
      v = dd * dd * sum / (2.0 * md * md * md * md * td);
    }
    var.push_back(v);
    terms.push_back(t);
  }
  // The noise types as allan() identifies them, from the lag-1 sums. allan()'s phase has the
  // whole record's mean rate removed, this one the first block's: it is allan()'s plus a ramp
  // of c per sample, c = the whole record's mean less the first block's = phase[N] / N, which
  // the d = 0 sums take out (the differenced series only shift by it).
  std::vector<std::optional<int>> identified;
  std::optional<int> carried;
  if (options.intervals && !options.alpha) {
    const int dmax = difference_order(options.kind);
    const double c = static_cast<double>((s.phase_origin + static_cast<long double>(s.phase_rel)) /
                                         static_cast<long double>(s.samples));
    const auto identify_at = [&](std::size_t m) -> std::optional<int> {
      const auto j = static_cast<std::size_t>(std::countr_zero(m));
      if (j >= s.lag1.size()) return std::nullopt;
      const auto id = s.lag1[j].identify(dmax, min_alpha(options.kind), c * static_cast<double>(m));
      return id ? std::optional<int>(id->alpha) : std::nullopt;
    };
    for (const std::size_t m : ms) identified.push_back(identify_at(m));
    const std::size_t longest = lag1_longest_octave_factor(s.samples);
    if (longest > 0) carried = identify_at(longest);
  }
  return allan_result_from_variances(ms, var, terms, s.samples, sample_rate_hz, options, identified,
                                     carried);
}

WaveletMoments DeviationStream::moments(double sample_rate_hz) {
  State& s = *state_;
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    throw core::InputError("rate",
                           fmt::format("must be positive and finite, got {}", sample_rate_hz));
  }
  if (s.samples < 32) {
    throw core::InputError("data", fmt::format("noise identification needs at least 32 samples "
                                               "(4 dyadic scales), got {}",
                                               s.samples));
  }
  if (!s.has(AllanKind::kAllan)) {
    throw core::InputError("kinds", "wavelet moments need the Allan variance accumulated");
  }
  AllanOptions options;
  options.intervals = false;
  const AllanResult r = result(sample_rate_hz, options);
  std::vector<double> avar;
  for (const AllanPoint& p : r.points) avar.push_back(p.deviation * p.deviation);
  return wavelet_moments_from_allan(avar, s.samples, sample_rate_hz);
}

}  // namespace calstand::solver

// Welch power spectral density and FFT autocorrelation, with FFTW.
#include "noise/psd.hpp"

#include <fftw3.h>
#include <fmt/format.h>

#include <cmath>
#include <memory>
#include <mutex>
#include <numbers>

#include "core/error.hpp"

namespace calstand::solver {
namespace {

// FFTW's planner keeps global state: plans are made (and destroyed) one at a time.
std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

// A real-to-complex and complex-to-real transform pair of length n with its own buffers
// (FFTW-aligned), destroyed with the object.
class RealFft {
 public:
  explicit RealFft(std::size_t n)
      : n_(n),
        real_(fftw_alloc_real(n), fftw_free),
        spectrum_(fftw_alloc_complex(n / 2 + 1), fftw_free) {
    if (!real_ || !spectrum_) throw std::bad_alloc();
    const std::lock_guard<std::mutex> lock(planner_mutex());
    const int len = static_cast<int>(n);
    forward_ = fftw_plan_dft_r2c_1d(len, real_.get(), spectrum_.get(), FFTW_ESTIMATE);
    backward_ = fftw_plan_dft_c2r_1d(len, spectrum_.get(), real_.get(), FFTW_ESTIMATE);
  }
  ~RealFft() {
    const std::lock_guard<std::mutex> lock(planner_mutex());
    fftw_destroy_plan(forward_);
    fftw_destroy_plan(backward_);
  }
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;

  double* real() { return real_.get(); }
  fftw_complex* spectrum() { return spectrum_.get(); }
  void forward() { fftw_execute(forward_); }
  void backward() { fftw_execute(backward_); }  // unnormalised: n times the inverse
  std::size_t size() const { return n_; }

 private:
  std::size_t n_;
  std::unique_ptr<double, decltype(&fftw_free)> real_;
  std::unique_ptr<fftw_complex, decltype(&fftw_free)> spectrum_;
  fftw_plan forward_ = nullptr;
  fftw_plan backward_ = nullptr;
};

void check_data(std::span<const double> data, double sample_rate_hz) {
  if (!std::isfinite(sample_rate_hz) || sample_rate_hz <= 0.0) {
    throw core::InputError("sample_rate_hz",
                           fmt::format("must be positive and finite, got {}", sample_rate_hz));
  }
  for (std::size_t i = 0; i < data.size(); ++i) {
    if (!std::isfinite(data[i])) {
      throw core::InputError("data", fmt::format("sample {} is not finite ({})", i, data[i]));
    }
  }
}

std::size_t auto_segment_length(std::size_t n) {
  // Largest power of two L with at least 8 half-overlapping segments: n >= 4.5 L.
  std::size_t len = 16;
  while (len * 2 <= (1U << 20) && 9 * (len * 2) <= 2 * n) len *= 2;
  return len;
}

}  // namespace

void WelchOptions::validate() const {
  if (!(overlap >= 0.0 && overlap < 1.0)) {
    throw core::InputError("overlap", fmt::format("must be in [0, 1), got {}", overlap));
  }
  if (segment_length != 0 && segment_length < 4) {
    throw core::InputError(
        "segment_length",
        fmt::format("must be at least 4 samples (or 0: automatic), got {}", segment_length));
  }
}

Psd welch_psd(std::span<const double> data, double sample_rate_hz, const WelchOptions& options) {
  options.validate();
  check_data(data, sample_rate_hz);
  const std::size_t len =
      options.segment_length != 0 ? options.segment_length : auto_segment_length(data.size());
  if (data.size() < len) {
    throw core::InputError("data", fmt::format("{} samples; a segment needs {}", data.size(), len));
  }
  // Periodic Hann window: its shifted copies at 50 % overlap sum to a constant.
  std::vector<double> window(len);
  double window_power = 0.0;
  for (std::size_t i = 0; i < len; ++i) {
    const double s = std::sin(std::numbers::pi * static_cast<double>(i) / static_cast<double>(len));
    window[i] = s * s;
    window_power += window[i] * window[i];
  }
  const auto hop = std::max<std::size_t>(
      1, static_cast<std::size_t>(std::lround(static_cast<double>(len) * (1.0 - options.overlap))));
  RealFft fft(len);
  const std::size_t bins = len / 2 + 1;
  Psd psd;
  psd.density.assign(bins, 0.0);
  for (std::size_t start = 0; start + len <= data.size(); start += hop) {
    double mean = 0.0;
    for (std::size_t i = 0; i < len; ++i) mean += data[start + i];
    mean /= static_cast<double>(len);
    for (std::size_t i = 0; i < len; ++i) fft.real()[i] = (data[start + i] - mean) * window[i];
    fft.forward();
    for (std::size_t k = 0; k < bins; ++k) {
      const double re = fft.spectrum()[k][0], im = fft.spectrum()[k][1];
      psd.density[k] += re * re + im * im;
    }
    ++psd.segments;
  }
  // |X|^2 / (fs sum w^2) is the two-sided density; double all but DC and Nyquist.
  const double scale = 1.0 / (sample_rate_hz * window_power * static_cast<double>(psd.segments));
  psd.frequency_hz.resize(bins);
  for (std::size_t k = 0; k < bins; ++k) {
    const bool edge = k == 0 || (len % 2 == 0 && k == bins - 1);
    psd.density[k] *= scale * (edge ? 1.0 : 2.0);
    psd.frequency_hz[k] = static_cast<double>(k) * sample_rate_hz / static_cast<double>(len);
  }
  psd.segment_length = len;
  psd.resolution_hz = sample_rate_hz / static_cast<double>(len);
  psd.enbw_hz = 1.5 * psd.resolution_hz;
  return psd;
}

Autocorrelation autocorrelation(std::span<const double> data, double sample_rate_hz,
                                std::size_t max_lag) {
  check_data(data, sample_rate_hz);
  const std::size_t n = data.size();
  if (n < 2) throw core::InputError("data", fmt::format("{} samples; need at least 2", n));
  max_lag = std::min(max_lag, n - 1);
  // Zero padding to at least 2n makes the circular correlation linear.
  std::size_t len = 1;
  while (len < 2 * n) len *= 2;
  double mean = 0.0;
  for (const double v : data) mean += v;
  mean /= static_cast<double>(n);
  RealFft fft(len);
  for (std::size_t i = 0; i < len; ++i) fft.real()[i] = i < n ? data[i] - mean : 0.0;
  fft.forward();
  const std::size_t bins = len / 2 + 1;
  for (std::size_t k = 0; k < bins; ++k) {
    const double re = fft.spectrum()[k][0], im = fft.spectrum()[k][1];
    fft.spectrum()[k][0] = re * re + im * im;
    fft.spectrum()[k][1] = 0.0;
  }
  fft.backward();
  Autocorrelation out;
  const double norm = 1.0 / (static_cast<double>(len) * static_cast<double>(n));
  const double c0 = fft.real()[0] * norm;
  if (!(c0 > 0.0)) throw core::InputError("data", "the data are constant: no autocorrelation");
  for (std::size_t k = 0; k <= max_lag; ++k) {
    const double c = fft.real()[k] * norm;
    out.lag_s.push_back(static_cast<double>(k) / sample_rate_hz);
    out.covariance.push_back(c);
    out.correlation.push_back(c / c0);
  }
  return out;
}

}  // namespace calstand::solver

#include <incise/core/error.hpp>
#include <incise/spectral/dominant_frequency.hpp>

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <memory>
#include <mutex>

namespace incise::spectral {
namespace {

// FFTW's planner is not thread safe; plans are created under this lock.
std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

struct FftwFree {
  void operator()(void* p) const { fftw_free(p); }
};

}  // namespace

FrequencyEstimate dominant_frequency(const std::vector<double>& samples, double dt) {
  INCISE_CHECK_PARAM(samples.size() >= 8, "dominant_frequency: need at least 8 samples");
  INCISE_CHECK_PARAM(dt > 0.0 && std::isfinite(dt), "dominant_frequency: dt must be positive");
  const int n = static_cast<int>(samples.size());
  double mean = 0.0;
  for (double s : samples) {
    INCISE_CHECK_PARAM(std::isfinite(s), "dominant_frequency: non-finite sample");
    mean += s;
  }
  mean /= n;
  // A signal whose deviations from its mean are at the round-off level of that mean (at most
  // n·eps·max|s| for the summed mean; 4× that here) does not oscillate resolvably: without this
  // a constant such as 0.1 would report the peak of its rounding noise.
  FrequencyEstimate est;
  est.resolution = 1.0 / (n * dt);
  double max_abs = 0.0, max_dev = 0.0;
  for (double s : samples) {
    max_abs = std::max(max_abs, std::abs(s));
    max_dev = std::max(max_dev, std::abs(s - mean));
  }
  if (max_dev <= 4.0 * n * std::numeric_limits<double>::epsilon() * max_abs) return est;
  const int nc = n / 2 + 1;
  std::unique_ptr<double, FftwFree> in(static_cast<double*>(fftw_malloc(sizeof(double) * n)));
  std::unique_ptr<fftw_complex, FftwFree> out(
      static_cast<fftw_complex*>(fftw_malloc(sizeof(fftw_complex) * nc)));
  fftw_plan plan;
  {
    std::lock_guard<std::mutex> lock(planner_mutex());
    plan = fftw_plan_dft_r2c_1d(n, in.get(), out.get(), FFTW_ESTIMATE);
  }
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < n; ++i) {
    const double w = 0.5 - 0.5 * std::cos(2.0 * pi * i / (n - 1));  // Hann window
    in.get()[i] = (samples[i] - mean) * w;
  }
  fftw_execute(plan);
  {
    std::lock_guard<std::mutex> lock(planner_mutex());
    fftw_destroy_plan(plan);
  }
  std::vector<double> mag(nc);
  for (int k = 0; k < nc; ++k) mag[k] = std::hypot(out.get()[k][0], out.get()[k][1]);

  // Skip the DC bin and its window leakage neighbour.
  int best = -1;
  double best_mag = 0.0;
  for (int k = 2; k < nc; ++k) {
    if (mag[k] > best_mag) {
      best_mag = mag[k];
      best = k;
    }
  }
  if (best < 0 || best_mag <= 0.0) return est;  // flat signal: no oscillation
  double offset = 0.0;
  if (best + 1 < nc && mag[best - 1] > 0.0 && mag[best + 1] > 0.0) {
    const double a = std::log(mag[best - 1]), b = std::log(mag[best]), c = std::log(mag[best + 1]);
    const double denom = a - 2.0 * b + c;
    if (denom < 0.0) offset = 0.5 * (a - c) / denom;
  }
  est.frequency = (best + offset) * est.resolution;
  est.amplitude = best_mag;
  return est;
}

}  // namespace incise::spectral

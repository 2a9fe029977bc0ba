#pragma once
/// \file dominant_frequency.hpp
/// FFTW-backed frequency estimate of a uniformly sampled signal, used to auto-tune the damping of
/// dynamic relaxation (thesis §4.4.1: η ≈ 2√λ₁ = 2ω₁, with ω₁ the lowest angular frequency).

#include <vector>

namespace incise::spectral {

/// Result of dominant_frequency().
struct FrequencyEstimate {
  double frequency = 0.0;   ///< dominant frequency (Hz), 0 when the signal does not oscillate
  double resolution = 0.0;  ///< FFT bin width 1/(N·dt) (Hz); the estimate is refined within a bin
  double amplitude = 0.0;   ///< |X(k)| of the peak bin (signal units × samples)
};

/// Frequency (Hz) of the largest non-DC peak of the real signal `samples` taken every `dt`
/// seconds. The mean is removed and a Hann window applied before the real-to-complex FFT
/// (FFTW r2c); the peak is refined by parabolic interpolation of log|X| over its neighbours.
/// Bins 0 and 1 (the mean and its window leakage) are skipped, so frequencies below 2/(N·dt)
/// are not resolved. A signal that does not oscillate (constant up to the round-off of its mean)
/// gives frequency = amplitude = 0. Throws ParameterError when samples.size() < 8 or dt ≤ 0 or
/// a sample is not finite.
FrequencyEstimate dominant_frequency(const std::vector<double>& samples, double dt);

}  // namespace incise::spectral

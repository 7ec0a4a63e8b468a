// Counter-based random numbers for the measurement models: every draw is a
// pure function of (seed, stream, counter), so results do not depend on the
// order or the threads that compute them, and the normal deviates come from
// our own Box–Muller transform instead of a library's distribution (which
// differs between standard libraries).
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

namespace truecut::sim::measure {

// SplitMix64's finaliser: a bijective 64-bit mix.
constexpr std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

constexpr std::uint64_t hash3(std::uint64_t seed, std::uint64_t stream, std::uint64_t counter) {
  return mix64(mix64(mix64(seed) ^ stream) ^ counter);
}

// Uniform in the open interval (0, 1): 53 random bits, centred in their cell.
inline double uniform_open(std::uint64_t seed, std::uint64_t stream, std::uint64_t counter) {
  return (static_cast<double>(hash3(seed, stream, counter) >> 11) + 0.5) * 0x1.0p-53;
}

// Standard normal deviate number `counter` of a stream (Box–Muller, cosine
// branch, from the uniforms 2·counter and 2·counter + 1).
inline double standard_normal(std::uint64_t seed, std::uint64_t stream, std::uint64_t counter) {
  const double u1 = uniform_open(seed, stream, 2 * counter);
  const double u2 = uniform_open(seed, stream, 2 * counter + 1);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace truecut::sim::measure

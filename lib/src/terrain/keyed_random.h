#pragma once
// Randoms indexed by a point's key rather than drawn from a stream, so the same point gets the same
// random whatever order, thread or run computes it (Fournier et al.'s "internal consistency").
#include <cmath>
#include <cstdint>
#include <numbers>
#include <utility>

#include "core/hash.h"

namespace lodkit::detail {

inline std::uint64_t base_vertex_key(std::uint64_t index) {
  return mix64(index + 0x9e3779b97f4a7c15ULL);
}

/// Order-independent: the key of the midpoint of (a, b) equals that of (b, a).
inline std::uint64_t midpoint_key(std::uint64_t a, std::uint64_t b) {
  if (a > b) std::swap(a, b);
  return mix64(a ^ mix64(b + 0x632be59bd9b4e019ULL));
}

inline std::uint64_t seeded(std::uint64_t key, std::uint64_t seed) {
  return mix64(key ^ mix64(seed ^ 0xd1b54a32d192ed03ULL));
}

/// A standard normal from the key: Box-Muller on the two 32-bit halves of the seeded hash (each
/// mapped into the open interval (0, 1), so the logarithm is finite).
inline double keyed_gaussian(std::uint64_t key, std::uint64_t seed) {
  const std::uint64_t h = seeded(key, seed);
  const double u1 = (static_cast<double>(h >> 32) + 0.5) * 0x1p-32;
  const double u2 = (static_cast<double>(h & 0xffffffffULL) + 0.5) * 0x1p-32;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

/// A fair coin from the key, independent of keyed_gaussian's bits.
inline bool keyed_coin(std::uint64_t key, std::uint64_t seed) {
  return (mix64(seeded(key, seed) ^ 0x8cb92ba72f3d8dd7ULL) >> 63) != 0;
}

}  // namespace lodkit::detail

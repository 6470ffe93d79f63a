#pragma once
// Exact-position keys for welding: two positions are the same vertex when their coordinates are
// bit-identical (after folding -0.0 onto +0.0).
#include <Eigen/Core>
#include <bit>
#include <cstdint>
#include <cstring>

namespace lodkit::detail {

struct PositionKey {
  std::uint64_t x, y, z;
  bool operator==(const PositionKey&) const = default;
};

inline std::uint64_t bits_of(double v) { return std::bit_cast<std::uint64_t>(v + 0.0); }

inline PositionKey position_key(double x, double y, double z) {
  return {bits_of(x), bits_of(y), bits_of(z)};
}

inline std::uint64_t mix64(std::uint64_t h) {  // splitmix64 finaliser
  h ^= h >> 30; h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27; h *= 0x94d049bb133111ebULL;
  return h ^ (h >> 31);
}

struct PositionKeyHash {
  std::size_t operator()(const PositionKey& k) const {
    return mix64(k.x ^ mix64(k.y ^ mix64(k.z)));
  }
};

}  // namespace lodkit::detail

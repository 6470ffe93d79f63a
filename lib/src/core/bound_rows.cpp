#include "core/bound_rows.h"

#include <algorithm>
#include <bit>
#include <cmath>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define LODKIT_HAVE_AVX2_KERNEL 1
#endif

namespace lodkit::detail {
namespace {

// Both kernels evaluate each plane as ((a x + b y) + c z) - d with separate multiplies and adds (no
// fused multiply-add), so they agree bit for bit.
void bounds_plain(const double* rows, std::size_t blocks, const Eigen::Vector3d& x, double* out, double* out_plane) {
  const double x0 = x[0], x1 = x[1], x2 = x[2];
  for (std::size_t b = 0; b < blocks; ++b, rows += 64)
    for (int l = 0; l < 4; ++l) {
      auto plane = [&](int row) {
        const double* r = rows + 4 * row + l;
        return r[0] * x0 + r[4] * x1 + r[8] * x2 - r[12];
      };
      const double n = plane(0), outside = std::max(std::max(plane(4), plane(8)), std::max(plane(12), 0.0));
      out[4 * b + l] = n * n + outside * outside;
      out_plane[4 * b + l] = n;
    }
}

#ifdef LODKIT_HAVE_AVX2_KERNEL
// Four planes (rows r, r + 4, r + 8, r + 12 of a block) at x.
__attribute__((target("avx2"))) inline __m256d planes_at(const double* r, __m256d x0, __m256d x1, __m256d x2) {
  const __m256d s = _mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(r), x0), _mm256_mul_pd(_mm256_loadu_pd(r + 4), x1));
  return _mm256_sub_pd(_mm256_add_pd(s, _mm256_mul_pd(_mm256_loadu_pd(r + 8), x2)), _mm256_loadu_pd(r + 12));
}

__attribute__((target("avx2"))) void bounds_avx2(const double* rows, std::size_t blocks, const Eigen::Vector3d& x,
                                                 double* out, double* out_plane) {
  const __m256d x0 = _mm256_set1_pd(x[0]), x1 = _mm256_set1_pd(x[1]), x2 = _mm256_set1_pd(x[2]);
  const __m256d zero = _mm256_setzero_pd();
  for (std::size_t b = 0; b < blocks; ++b, rows += 64) {
    const __m256d n = planes_at(rows, x0, x1, x2);
    const __m256d outside = _mm256_max_pd(_mm256_max_pd(planes_at(rows + 16, x0, x1, x2), planes_at(rows + 32, x0, x1, x2)),
                                          _mm256_max_pd(planes_at(rows + 48, x0, x1, x2), zero));
    _mm256_storeu_pd(out + 4 * b, _mm256_add_pd(_mm256_mul_pd(n, n), _mm256_mul_pd(outside, outside)));
    _mm256_storeu_pd(out_plane + 4 * b, n);
  }
}

// Bit i: bounds[i] compared with `value` holds (kCompare: _CMP_LT_OQ or _CMP_EQ_OQ).
template <int kCompare>
__attribute__((target("avx2"))) std::uint64_t compare_avx2(const double* bounds, std::size_t blocks, double value) {
  const __m256d l = _mm256_set1_pd(value);
  std::uint64_t mask = 0;
  for (std::size_t b = 0; b < blocks; ++b)
    mask |= std::uint64_t(_mm256_movemask_pd(_mm256_cmp_pd(_mm256_loadu_pd(bounds + 4 * b), l, kCompare))) << (4 * b);
  return mask;
}

// The least of bounds[0, m), the padding of the last block left out.
__attribute__((target("avx2"))) double least_avx2(const double* bounds, std::size_t m) {
  const std::size_t whole = m / 4;
  __m256d least = _mm256_set1_pd(INFINITY);
  for (std::size_t b = 0; b < whole; ++b) least = _mm256_min_pd(least, _mm256_loadu_pd(bounds + 4 * b));
  const __m128d half = _mm_min_pd(_mm256_castpd256_pd128(least), _mm256_extractf128_pd(least, 1));
  double out = _mm_cvtsd_f64(_mm_min_sd(half, _mm_unpackhi_pd(half, half)));
  for (std::size_t i = 4 * whole; i < m; ++i) out = std::min(out, bounds[i]);
  return out;
}

bool has_avx2() {
  __builtin_cpu_init();  // this may run before the constructors that would otherwise do it
  return __builtin_cpu_supports("avx2");
}
bool use_avx2 = has_avx2();  // (only tests change it, with no scoring under way)
#endif

}  // namespace

void BoundRows::use_vector_kernel(bool on) {
#ifdef LODKIT_HAVE_AVX2_KERNEL
  use_avx2 = on && has_avx2();
#else
  (void)on;
#endif
}

const double* BoundRows::lower_bounds2(const Eigen::Vector3d& x) {
#ifdef LODKIT_HAVE_AVX2_KERNEL
  if (use_avx2) {
    bounds_avx2(rows_.data(), blocks_, x, bounds_.data(), planes_.data());
    return bounds_.data();
  }
#endif
  bounds_plain(rows_.data(), blocks_, x, bounds_.data(), planes_.data());
  return bounds_.data();
}

std::uint64_t BoundRows::below(double limit) const {
  std::uint64_t mask = 0;
  const std::size_t blocks = std::min<std::size_t>(blocks_, 16);  // (bits for the first 64 only)
#ifdef LODKIT_HAVE_AVX2_KERNEL
  if (use_avx2) {
    mask = compare_avx2<_CMP_LT_OQ>(bounds_.data(), blocks, limit);
  } else
#endif
  {
    for (std::size_t i = 0; i < 4 * blocks; ++i) mask |= std::uint64_t(bounds_[i] < limit) << i;
  }
  return m_ >= 64 ? mask : mask & ((std::uint64_t(1) << m_) - 1);
}

std::size_t BoundRows::lowest() const {
#ifdef LODKIT_HAVE_AVX2_KERNEL
  if (use_avx2 && m_ <= 64) {
    // The least value, then the first triangle that has it: the same as a scan keeping the first.
    const std::uint64_t at = compare_avx2<_CMP_EQ_OQ>(bounds_.data(), blocks_, least_avx2(bounds_.data(), m_));
    if (at) return std::size_t(std::countr_zero(at));  // (none only for NaN bounds)
  }
#endif
  std::size_t first = 0;
  for (std::size_t k = 1; k < m_; ++k)
    if (bounds_[k] < bounds_[first]) first = k;
  return first;
}

}  // namespace lodkit::detail

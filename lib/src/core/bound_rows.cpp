#include "core/bound_rows.h"

#include <algorithm>

// The loop vectorises four-wide where the CPU has AVX2, chosen at load time.
#if defined(__x86_64__) && defined(__GNUC__)
#define LODKIT_AVX2_CLONE __attribute__((target_clones("avx2", "default")))
#else
#define LODKIT_AVX2_CLONE
#endif

namespace lodkit::detail {
namespace {

LODKIT_AVX2_CLONE void bounds_of_rows(const double* __restrict planes, std::size_t m, const Eigen::Vector3d& x,
                                      double* __restrict out, double* __restrict out_plane) {
  const double x0 = x[0], x1 = x[1], x2 = x[2];
  auto row = [&](int r) { return planes + std::size_t(r) * m; };
  const double *nx = row(0), *ny = row(1), *nz = row(2), *no = row(3);
  const double *ax = row(4), *ay = row(5), *az = row(6), *ao = row(7);
  const double *bx = row(8), *by = row(9), *bz = row(10), *bo = row(11);
  const double *cx = row(12), *cy = row(13), *cz = row(14), *co = row(15);
  for (std::size_t i = 0; i < m; ++i) {
    const double plane = nx[i] * x0 + ny[i] * x1 + nz[i] * x2 - no[i];
    const double a = ax[i] * x0 + ay[i] * x1 + az[i] * x2 - ao[i];
    const double b = bx[i] * x0 + by[i] * x1 + bz[i] * x2 - bo[i];
    const double c = cx[i] * x0 + cy[i] * x1 + cz[i] * x2 - co[i];
    const double outside = std::max(std::max(a, b), std::max(c, 0.0));
    out[i] = plane * plane + outside * outside;
    out_plane[i] = plane;
  }
}

}  // namespace

const double* BoundRows::lower_bounds2(const Eigen::Vector3d& x) {
  bounds_of_rows(rows_.data(), m_, x, bounds_.data(), planes_.data());
  return bounds_.data();
}

}  // namespace lodkit::detail

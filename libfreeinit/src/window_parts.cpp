// The window recorder's per-return loops (window_parts.h): without branches and over arrays that
// do not overlap (__restrict), so that the compiler vectorizes them; built for AVX2 as well as the
// baseline, chosen at load time. The same float operations in the same order as the scalar forms
// (RestCells::cellOf, the map and residual formulas) and no FMA contraction (AVX2 alone does not
// enable FMA): the same results on either build.
#include "window_parts.h"

#include <algorithm>
#include <cmath>

namespace freeinit::detail::recorder_kernels {

#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
#define FREEINIT_RECORDER_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FREEINIT_RECORDER_CLONES
#endif

FREEINIT_RECORDER_CLONES
void cellsOf(std::size_t n, const float* __restrict x, const float* __restrict y,
             const float* __restrict z, std::uint16_t* __restrict cell) {
  constexpr int kSide = RestCells::kSide;
  for (std::size_t i = 0; i < n; ++i) {
    const float px = x[i], py = y[i], pz = z[i];
    const float l1 = std::abs(px) + std::abs(py) + std::abs(pz);
    const float u0 = px / l1, v0 = py / l1;
    const float fu = (1.0f - std::abs(v0)) * (u0 >= 0 ? 1.0f : -1.0f);
    const float fv = (1.0f - std::abs(u0)) * (v0 >= 0 ? 1.0f : -1.0f);
    const bool lower = pz < 0;
    const float u = lower ? fu : u0, v = lower ? fv : v0;
    const int bu = std::clamp(static_cast<int>((u + 1.0f) * 0.5f * kSide), 0, kSide - 1);
    const int bv = std::clamp(static_cast<int>((v + 1.0f) * 0.5f * kSide), 0, kSide - 1);
    // The number of range-bin edges at or below the squared range: cellOf's bisection counts
    // the same (the edges are sorted), and never more than kRangeBins - 1.
    const float r2 = px * px + (py * py + pz * pz);  // as Eigen's squaredNorm() sums
    int rb = 0;
#pragma GCC unroll 32
    for (const float e : RestCells::kRangeEdges2) rb += e <= r2 ? 1 : 0;
    cell[i] = static_cast<std::uint16_t>((bu * kSide + bv) * RestCells::kRangeBins + rb);
  }
}

FREEINIT_RECORDER_CLONES
void mapReturns(std::size_t n, const NodeMap& m, float* __restrict x, float* __restrict y,
                float* __restrict z, float* __restrict tau) {
  const float a00 = m.A[0], a01 = m.A[1], a02 = m.A[2], a10 = m.A[3], a11 = m.A[4], a12 = m.A[5],
              a20 = m.A[6], a21 = m.A[7], a22 = m.A[8];
  const float b00 = m.B[0], b01 = m.B[1], b02 = m.B[2], b10 = m.B[3], b11 = m.B[4], b12 = m.B[5],
              b20 = m.B[6], b21 = m.B[7], b22 = m.B[8];
  const float ax = m.a[0], ay = m.a[1], az = m.a[2], bx = m.b[0], by = m.b[1], bz = m.b[2],
              t_node = m.time;
  for (std::size_t i = 0; i < n; ++i) {
    const float px = x[i], py = y[i], pz = z[i], t = tau[i];
    // A p_l + a + tau (B p_l + b), each sum in the order Eigen's float products take it.
    x[i] = ((a00 * px + a01 * py) + a02 * pz) + ax + t * (((b00 * px + b01 * py) + b02 * pz) + bx);
    y[i] = ((a10 * px + a11 * py) + a12 * pz) + ay + t * (((b10 * px + b11 * py) + b12 * pz) + by);
    z[i] = ((a20 * px + a21 * py) + a22 * pz) + az + t * (((b20 * px + b21 * py) + b22 * pz) + bz);
    tau[i] = t_node + t;
  }
}

FREEINIT_RECORDER_CLONES
void dopplerResiduals(std::size_t n, const float (&q)[9], float inv_h, const float* __restrict x,
                      const float* __restrict y, const float* __restrict z,
                      const float* __restrict tau, const float* __restrict doppler,
                      float* __restrict residual) {
  const float q0x = q[0], q0y = q[1], q0z = q[2], q1x = q[3], q1y = q[4], q1z = q[5], q2x = q[6],
              q2y = q[7], q2z = q[8];
  for (std::size_t i = 0; i < n; ++i) {
    const float s = tau[i] * inv_h;
    const float vx = q0x + s * (q1x + s * q2x), vy = q0y + s * (q1y + s * q2y),
                vz = q0z + s * (q1z + s * q2z);
    const float px = x[i], py = y[i], pz = z[i];
    // p_l.dot(v) / p_l.norm(), each sum in the order Eigen takes a 3-vector's (x + (y + z)).
    residual[i] =
        doppler[i] + (px * vx + (py * vy + pz * vz)) / std::sqrt(px * px + (py * py + pz * pz));
  }
}

}  // namespace freeinit::detail::recorder_kernels

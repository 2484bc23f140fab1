// The window recorder's per-return loops (window_parts.h): without branches and over arrays that
// do not overlap (__restrict), so that the compiler vectorizes them; built for AVX-512 and AVX2 as
// well as the baseline, chosen at load time (vector_clones.h). The same float operations in the
// same order as the scalar forms (RestCells::cellOf, the map and residual formulas) and no FMA
// contraction: the same results on every build.
#include "joint/window_parts.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>

#include "joint/vector_clones.h"

namespace freeinit::detail::recorder_kernels {

namespace {

// Four floats, an SSE register in every build: the transposes below move bits and compute
// nothing, so their results are those of the scalar copy.
typedef float V4 __attribute__((vector_size(16)));

#if defined(__clang__)
#define FREEINIT_SHUFFLE(a, b, i0, i1, i2, i3) __builtin_shufflevector(a, b, i0, i1, i2, i3)
#else
typedef int V4i __attribute__((vector_size(16)));
#define FREEINIT_SHUFFLE(a, b, i0, i1, i2, i3) __builtin_shuffle(a, b, V4i{i0, i1, i2, i3})
#endif

/// Rows a, b, c, d of a 4 x 4 block into its columns: a = (a0, b0, c0, d0), b = (a1, b1, ...).
inline void transpose(V4& a, V4& b, V4& c, V4& d) {
  const V4 ab_lo = FREEINIT_SHUFFLE(a, b, 0, 4, 1, 5), ab_hi = FREEINIT_SHUFFLE(a, b, 2, 6, 3, 7);
  const V4 cd_lo = FREEINIT_SHUFFLE(c, d, 0, 4, 1, 5), cd_hi = FREEINIT_SHUFFLE(c, d, 2, 6, 3, 7);
  a = FREEINIT_SHUFFLE(ab_lo, cd_lo, 0, 1, 4, 5);
  b = FREEINIT_SHUFFLE(ab_lo, cd_lo, 2, 3, 6, 7);
  c = FREEINIT_SHUFFLE(ab_hi, cd_hi, 0, 1, 4, 5);
  d = FREEINIT_SHUFFLE(ab_hi, cd_hi, 2, 3, 6, 7);
}

#undef FREEINIT_SHUFFLE

V4 load4(const float* p) {
  V4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

void store4(float* p, const V4& v) { std::memcpy(p, &v, sizeof v); }

}  // namespace

FREEINIT_VECTOR_CLONES
std::size_t layOut(const DopplerPoint* __restrict p, std::size_t count, std::size_t step,
                   double stamp, double t_node, const UsablePoints& usable, float* __restrict x,
                   float* __restrict y, float* __restrict z, float* __restrict intensity,
                   float* __restrict doppler, float* __restrict tau,
                   std::uint8_t* __restrict usable_out) {
  // First the fields, the time offset into tau; then, over those arrays, tau and the verdict in
  // a loop the compiler vectorizes (over the points themselves, 28 bytes apart, it would gather
  // each lane).
  static_assert(sizeof(DopplerPoint) == 7 * sizeof(float) &&
                offsetof(DopplerPoint, doppler) == 3 * sizeof(float) &&
                offsetof(DopplerPoint, time_offset) == 4 * sizeof(float) &&
                offsetof(DopplerPoint, intensity) == 5 * sizeof(float));
  std::size_t i = 0;
  if (step == 1) {
    // Four consecutive points are 28 floats: (x, y, z, Doppler) of each at 7 k and (time
    // offset, intensity, ...) at 7 k + 4, two 4 x 4 transposes. A block needs a point after it
    // (the last of those loads reaches one float into it).
    const float* f = reinterpret_cast<const float*>(p);
    for (; i + 4 < count; i += 4, f += 28) {
      V4 a0 = load4(f), a1 = load4(f + 7), a2 = load4(f + 14), a3 = load4(f + 21);
      V4 b0 = load4(f + 4), b1 = load4(f + 11), b2 = load4(f + 18), b3 = load4(f + 25);
      transpose(a0, a1, a2, a3);
      transpose(b0, b1, b2, b3);
      store4(x + i, a0);
      store4(y + i, a1);
      store4(z + i, a2);
      store4(doppler + i, a3);
      store4(tau + i, b0);
      store4(intensity + i, b1);
    }
  }
  for (; i < count; ++i) {
    const DopplerPoint& q = p[i * step];
    x[i] = q.p_l.x();
    y[i] = q.p_l.y();
    z[i] = q.p_l.z();
    doppler[i] = q.doppler;
    tau[i] = q.time_offset;
    intensity[i] = q.intensity;
  }
  const UsablePoints test = usable;  // a copy: its limits stay in registers
  std::size_t n = 0;
  for (std::size_t k = 0; k < count; ++k) {
    DopplerPoint q;
    q.p_l = Eigen::Vector3f(x[k], y[k], z[k]);
    q.doppler = doppler[k];
    q.time_offset = tau[k];
    const std::uint8_t u = test(q) ? 1 : 0;
    usable_out[k] = u;
    n += u;
    tau[k] = static_cast<float>(stamp + static_cast<double>(q.time_offset) - t_node);
  }
  return n;
}

FREEINIT_VECTOR_CLONES
void cellsOf(std::size_t n, const float* __restrict x, const float* __restrict y,
             const float* __restrict z, std::uint16_t* __restrict cell) {
  // Eight returns at a time as vector code (an AVX register, or two SSE2 ones in the baseline
  // build), so that each step of RestCells::cellOf is one operation for the eight: the range
  // bin a compare and a subtract per edge.
  typedef float V8 __attribute__((vector_size(32)));
  typedef std::int32_t V8i __attribute__((vector_size(32)));
  typedef std::uint16_t V8u16 __attribute__((vector_size(16)));
  constexpr int kSide = RestCells::kSide;
  const V8 zero = V8{} + 0.0f, one = zero + 1.0f, minus_one = zero - 1.0f;
  // (Helpers write through references: a vector returned by value would change the ABI
  // between the builds.)
  auto abs = [](const V8& v, V8& a) {
    V8i b;
    std::memcpy(&b, &v, sizeof b);
    b &= 0x7fffffff;
    std::memcpy(&a, &b, sizeof a);
  };
  auto bin = [](const V8& w, V8i& b) {
    b = __builtin_convertvector((w + 1.0f) * 0.5f * static_cast<float>(kSide), V8i);
    b = b < 0 ? V8i{} : b;
    b = b > kSide - 1 ? V8i{} + (kSide - 1) : b;
  };
  constexpr std::size_t kEdges = RestCells::kRangeEdges2.size();
  V8 edges[kEdges];
  for (std::size_t k = 0; k < kEdges; ++k) edges[k] = zero + RestCells::kRangeEdges2[k];
  auto cells8 = [&](const float* px_, const float* py_, const float* pz_, std::uint16_t* out) {
    V8 px, py, pz, ax, ay, az;
    std::memcpy(&px, px_, sizeof px);
    std::memcpy(&py, py_, sizeof py);
    std::memcpy(&pz, pz_, sizeof pz);
    abs(px, ax);
    abs(py, ay);
    abs(pz, az);
    const V8 l1 = ax + ay + az;
    const V8 u0 = px / l1, v0 = py / l1;
    V8 au0, av0;
    abs(u0, au0);
    abs(v0, av0);
    const V8 fu = (one - av0) * (u0 >= zero ? one : minus_one);
    const V8 fv = (one - au0) * (v0 >= zero ? one : minus_one);
    const V8i lower = pz < zero;
    V8i bu, bv;
    bin(lower ? fu : u0, bu);
    bin(lower ? fv : v0, bv);
    // The number of range-bin edges at or below the squared range: cellOf's bisection counts
    // the same (the edges are sorted), and never more than kRangeBins - 1.
    const V8 r2 = px * px + (py * py + pz * pz);  // as Eigen's squaredNorm() sums
    V8i rb = V8i{};
#pragma GCC unroll 32
    for (const V8& edge : edges) rb -= edge <= r2;  // true is -1
    const V8i c = (bu * kSide + bv) * static_cast<std::int32_t>(RestCells::kRangeBins) + rb;
    const V8u16 c16 = __builtin_convertvector(c, V8u16);
    std::memcpy(out, &c16, sizeof c16);
  };
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) cells8(x + i, y + i, z + i, cell + i);
  if (i < n) {  // the last returns, the other lanes at (1, 1, 1)
    float px[8], py[8], pz[8];
    std::fill(px, px + 8, 1.0f);
    std::fill(py, py + 8, 1.0f);
    std::fill(pz, pz + 8, 1.0f);
    std::copy(x + i, x + n, px);
    std::copy(y + i, y + n, py);
    std::copy(z + i, z + n, pz);
    std::uint16_t out[8];
    cells8(px, py, pz, out);
    std::copy(out, out + (n - i), cell + i);
  }
}

FREEINIT_VECTOR_CLONES
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

FREEINIT_VECTOR_CLONES
std::size_t verdicts(std::size_t n, const DopplerInertialFilter& filter, std::uint16_t no_cell,
                     std::uint16_t* __restrict cell, float* __restrict residual) {
  // Three loops the compiler vectorizes; the verdict as a mask, not a branch (the rejected
  // returns are scattered).
  for (std::size_t j = 0; j < n; ++j) {
    const std::uint16_t rejected = filter.pointAccepted(j) ? 0 : 0xffff;
    cell[j] = static_cast<std::uint16_t>((cell[j] & ~rejected) | (no_cell & rejected));
  }
  std::size_t accepted = 0;
  for (std::size_t j = 0; j < n; ++j) accepted += cell[j] != no_cell ? 1 : 0;
  for (std::size_t j = 0; j < n; ++j) residual[j] = static_cast<float>(filter.pointResidual(j));
  return accepted;
}

FREEINIT_VECTOR_CLONES
std::size_t splitReturns(std::size_t n, const float* __restrict arrays,
                         const std::uint16_t* __restrict cell, std::uint16_t no_cell,
                         MapPoint* __restrict map, MapPoint* __restrict rejected,
                         std::size_t& dropped) {
  static_assert(sizeof(MapPoint) == 7 * sizeof(float));
  const float *x = arrays, *y = x + n, *z = x + 2 * n, *in = x + 3 * n, *d = x + 4 * n,
              *tau = x + 5 * n, *res = x + 6 * n;
  float* out = reinterpret_cast<float*>(map);
  float* out_rejected = reinterpret_cast<float*>(rejected);
  std::size_t kept = 0, dropped_here = 0;
  // One return: written to both lists (no branch on its verdict, which is as good as random
  // where the rejected returns are scattered), the list it belongs to advancing.
  auto one = [&](std::size_t j) {
    const float p[7] = {x[j], y[j], z[j], in[j], res[j], d[j], tau[j]};
    float *a = out + 7 * kept, *b = out_rejected + 7 * dropped_here;
    for (int f = 0; f < 7; ++f) a[f] = p[f];
    for (int f = 0; f < 7; ++f) b[f] = p[f];
    const std::size_t in_map = cell[j] != no_cell ? 1 : 0;
    kept += in_map;
    dropped_here += 1 - in_map;
  };
  // Four returns all in the map (the usual case) at once: MapPoint k of them is (x, y, z,
  // intensity) of return k and then (residual, Doppler, tau) of it and the x of return k + 1,
  // which the next MapPoint writes again: two 4 x 4 transposes. A block needs a return after it
  // (whose x the last write takes); the others go one by one.
  std::size_t j = 0;
  for (; j + 4 < n; j += 4) {
    const bool all = (cell[j] != no_cell) & (cell[j + 1] != no_cell) & (cell[j + 2] != no_cell) &
                     (cell[j + 3] != no_cell);
    if (!all) {
      for (std::size_t l = 0; l < 4; ++l) one(j + l);
      continue;
    }
    V4 a0 = load4(x + j), a1 = load4(y + j), a2 = load4(z + j), a3 = load4(in + j);
    V4 b0 = load4(res + j), b1 = load4(d + j), b2 = load4(tau + j), b3 = load4(x + j + 1);
    transpose(a0, a1, a2, a3);
    transpose(b0, b1, b2, b3);
    float* o = out + 7 * kept;
    store4(o, a0);
    store4(o + 4, b0);
    store4(o + 7, a1);
    store4(o + 11, b1);
    store4(o + 14, a2);
    store4(o + 18, b2);
    store4(o + 21, a3);
    store4(o + 25, b3);
    kept += 4;
  }
  for (; j < n; ++j) one(j);
  dropped += dropped_here;
  return kept;
}

namespace {
/// runTerms' loop, each array its own restrict pointer (with all nine from one, the compiler
/// cannot vectorize the stores).
FREEINIT_VECTOR_CLONES
void runTermsInto(std::size_t n, float inv_h, const float* __restrict x, const float* __restrict y,
                  const float* __restrict z, const float* __restrict tau, float* __restrict d0x,
                  float* __restrict d0y, float* __restrict d0z, float* __restrict d1x,
                  float* __restrict d1y, float* __restrict d1z, float* __restrict d2x,
                  float* __restrict d2y, float* __restrict d2z) {
  for (std::size_t i = 0; i < n; ++i) {
    const float s = tau[i] * inv_h;
    const float px = x[i], py = y[i], pz = z[i];
    const float inv = 1.0f / std::sqrt(px * px + (py * py + pz * pz));
    const float ux = px * inv, uy = py * inv, uz = pz * inv;
    d0x[i] = ux;
    d0y[i] = uy;
    d0z[i] = uz;
    d1x[i] = s * ux;
    d1y[i] = s * uy;
    d1z[i] = s * uz;
    d2x[i] = s * (s * ux);
    d2y[i] = s * (s * uy);
    d2z[i] = s * (s * uz);
  }
}
}  // namespace

void runTerms(std::size_t n, float inv_h, const float* x, const float* y, const float* z,
              const float* tau, float* terms) {
  runTermsInto(n, inv_h, x, y, z, tau, terms, terms + n, terms + 2 * n, terms + 3 * n,
               terms + 4 * n, terms + 5 * n, terms + 6 * n, terms + 7 * n, terms + 8 * n);
}

std::size_t cellRuns(std::size_t n, const std::uint16_t* __restrict cell, std::uint16_t no_cell,
                     const float* __restrict terms, const float* __restrict doppler,
                     CellRun* __restrict runs) {
  const float *d0x = terms, *d0y = terms + n, *d0z = terms + 2 * n, *d1x = terms + 3 * n,
              *d1y = terms + 4 * n, *d1z = terms + 5 * n, *d2x = terms + 6 * n,
              *d2y = terms + 7 * n, *d2z = terms + 8 * n;
  std::size_t m = 0, j = 0;
  while (j < n) {
    const std::uint16_t c = cell[j];
    if (c == no_cell) {
      ++j;
      continue;
    }
    // The run's sums, each its own variable, so that they stay in registers while it lasts.
    float sz = 0, s0x = 0, s0y = 0, s0z = 0, s1x = 0, s1y = 0, s1z = 0, s2x = 0, s2y = 0, s2z = 0;
    std::uint32_t count = 0;
    for (; j < n && (cell[j] == c || cell[j] == no_cell); ++j) {
      if (cell[j] == no_cell) continue;
      sz += doppler[j];
      s0x += d0x[j];
      s0y += d0y[j];
      s0z += d0z[j];
      s1x += d1x[j];
      s1y += d1y[j];
      s1z += d1z[j];
      s2x += d2x[j];
      s2y += d2y[j];
      s2z += d2z[j];
      ++count;
    }
    CellRun& r = runs[m++];
    r.cell = c;
    r.count = count;
    r.doppler = sz;
    const float d[9] = {s0x, s0y, s0z, s1x, s1y, s1z, s2x, s2y, s2z};
    std::memcpy(r.d, d, sizeof d);
  }
  return m;
}

}  // namespace freeinit::detail::recorder_kernels

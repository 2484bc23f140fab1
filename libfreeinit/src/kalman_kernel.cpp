#include "kalman_kernel.h"

#include <cmath>
#include <cstddef>
#include <cstring>

namespace freeinit::detail {
namespace {

// Four doubles: an AVX register, or two SSE2 ones in the baseline build. The code below runs the
// same operations in the same order per lane whatever the width (no fused multiply-add in
// either), so both builds give the same results; built for both, chosen at load time. The sizes
// are template parameters: every loop below has a known trip count and is unrolled, and every
// lane it reads is known at compile time.
typedef double V4 __attribute__((vector_size(32)));

constexpr int kLd = 19;        ///< P's leading dimension (DopplerInertialFilter::kStateDim)
constexpr int kSkipBegin = 3;  ///< H's position columns, zero: skipped
constexpr int kSkipEnd = 6;
constexpr bool used(int c) { return c < kSkipBegin || c >= kSkipEnd; }

// Every loop of the update unrolled: its trip count is a template parameter.
#define FREEINIT_UNROLL _Pragma("GCC unroll 20")

/// n values (n <= 4) from p into v, the other lanes zero.
inline void load(const double* p, int n, V4& v) {
  v = V4{0, 0, 0, 0};
  std::memcpy(&v, p, static_cast<std::size_t>(n) * sizeof(double));
}

inline void store(const V4& v, int n, double* p) {
  std::memcpy(p, &v, static_cast<std::size_t>(n) * sizeof(double));
}

/// The rows of chunk q of a column of n.
constexpr int rows(int n, int q) { return n - 4 * q < 4 ? n - 4 * q : 4; }

template <int D, int R>
__attribute__((always_inline)) inline void update(double* P, const double* H,
                                                  const double* innovation, double* dx) {
  constexpr int kQ = (D + 3) / 4;   // chunks of four of a state column
  constexpr int kRq = (R + 3) / 4;  // chunks of four of a row column
  // P by columns, in chunks of four rows (lanes past D zero).
  V4 Pc[D][kQ];
  FREEINIT_UNROLL
  for (int c = 0; c < D; ++c) {
    FREEINIT_UNROLL
    for (int q = 0; q < kQ; ++q) load(P + c * kLd + 4 * q, rows(D, q), Pc[c][q]);
  }
  // H's columns, in chunks of four rows (lanes past R zero).
  V4 Hc[D][kRq];
  FREEINIT_UNROLL
  for (int c = 0; c < D; ++c) {
    FREEINIT_UNROLL
    for (int q = 0; q < kRq; ++q) load(H + c * R + 4 * q, rows(R, q), Hc[c][q]);
  }
  // A = P H^T (D x R): column j = sum over c of P(:, c) H(j, c).
  V4 A[R][kQ];
  FREEINIT_UNROLL
  for (int j = 0; j < R; ++j) {
    FREEINIT_UNROLL
    for (int q = 0; q < kQ; ++q) A[j][q] = V4{0, 0, 0, 0};
    FREEINIT_UNROLL
    for (int c = 0; c < D; ++c) {
      if (!used(c)) continue;
      const double h = H[c * R + j];
      FREEINIT_UNROLL
      for (int q = 0; q < kQ; ++q) A[j][q] += Pc[c][q] * h;
    }
  }
  // S = H A + I (R x R), column j = sum over c of H(:, c) A(c, j); then S = L L^T, L in the
  // lower triangle (S >= I: the factorization cannot fail).
  double S[R][R];  // S[i][j]: row i, column j
  FREEINIT_UNROLL
  for (int j = 0; j < R; ++j) {
    V4 s[kRq];
    FREEINIT_UNROLL
    for (int q = 0; q < kRq; ++q) s[q] = V4{0, 0, 0, 0};
    FREEINIT_UNROLL
    for (int c = 0; c < D; ++c) {
      if (!used(c)) continue;
      const double a = A[j][c / 4][c % 4];
      FREEINIT_UNROLL
      for (int q = 0; q < kRq; ++q) s[q] += Hc[c][q] * a;
    }
    FREEINIT_UNROLL
    for (int i = 0; i < R; ++i) S[i][j] = s[i / 4][i % 4];
    S[j][j] += 1.0;
  }
  FREEINIT_UNROLL
  for (int j = 0; j < R; ++j) {
    double diag = S[j][j];
    FREEINIT_UNROLL
    for (int k = 0; k < j; ++k) diag -= S[j][k] * S[j][k];
    diag = std::sqrt(diag);
    S[j][j] = diag;
    FREEINIT_UNROLL
    for (int i = j + 1; i < R; ++i) {
      double v = S[i][j];
      FREEINIT_UNROLL
      for (int k = 0; k < j; ++k) v -= S[i][k] * S[j][k];
      S[i][j] = v / diag;
    }
  }
  // Y = A L^-T (in A), z = L^-1 innovation.
  double z[R];
  FREEINIT_UNROLL
  for (int j = 0; j < R; ++j) {
    double zj = innovation[j];
    FREEINIT_UNROLL
    for (int i = 0; i < j; ++i) {
      const double l = S[j][i];
      FREEINIT_UNROLL
      for (int q = 0; q < kQ; ++q) A[j][q] -= A[i][q] * l;
      zj -= l * z[i];
    }
    FREEINIT_UNROLL
    for (int q = 0; q < kQ; ++q) A[j][q] /= S[j][j];
    z[j] = zj / S[j][j];
  }
  // dx += Y z; P -= Y Y^T, element (i, c) summed over j in the same order as (c, i).
  FREEINIT_UNROLL
  for (int q = 0; q < kQ; ++q) {
    V4 step = V4{0, 0, 0, 0};
    FREEINIT_UNROLL
    for (int j = 0; j < R; ++j) step += A[j][q] * z[j];
    V4 x;
    load(dx + 4 * q, rows(D, q), x);
    store(x + step, rows(D, q), dx + 4 * q);
  }
  FREEINIT_UNROLL
  for (int c = 0; c < D; ++c) {
    FREEINIT_UNROLL
    for (int q = 0; q < kQ; ++q) {
      V4 yy = V4{0, 0, 0, 0};
      FREEINIT_UNROLL
      for (int j = 0; j < R; ++j) yy += A[j][q] * A[j][c / 4][c % 4];
      store(Pc[c][q] - yy, rows(D, q), P + c * kLd + 4 * q);
    }
  }
}

}  // namespace

#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
#define FREEINIT_KALMAN_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FREEINIT_KALMAN_CLONES
#endif

// One function per size, each built for AVX2 and the baseline (target_clones does not apply to
// templates).
FREEINIT_KALMAN_CLONES
void kalmanUpdate15x9(double* P, const double* H, const double* innovation, double* dx) {
  update<15, 9>(P, H, innovation, dx);
}
FREEINIT_KALMAN_CLONES
void kalmanUpdate19x9(double* P, const double* H, const double* innovation, double* dx) {
  update<19, 9>(P, H, innovation, dx);
}
FREEINIT_KALMAN_CLONES
void kalmanUpdate15x6(double* P, const double* H, const double* innovation, double* dx) {
  update<15, 6>(P, H, innovation, dx);
}
FREEINIT_KALMAN_CLONES
void kalmanUpdate19x6(double* P, const double* H, const double* innovation, double* dx) {
  update<19, 6>(P, H, innovation, dx);
}

template <>
void kalmanUpdateKernel<15, 9>(double* P, const double* H, const double* innovation, double* dx) {
  kalmanUpdate15x9(P, H, innovation, dx);
}
template <>
void kalmanUpdateKernel<19, 9>(double* P, const double* H, const double* innovation, double* dx) {
  kalmanUpdate19x9(P, H, innovation, dx);
}
template <>
void kalmanUpdateKernel<15, 6>(double* P, const double* H, const double* innovation, double* dx) {
  kalmanUpdate15x6(P, H, innovation, dx);
}
template <>
void kalmanUpdateKernel<19, 6>(double* P, const double* H, const double* innovation, double* dx) {
  kalmanUpdate19x6(P, H, innovation, dx);
}

}  // namespace freeinit::detail

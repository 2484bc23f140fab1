#include "joint/filter_kernels.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "joint/vector_clones.h"

namespace freeinit::detail {
namespace {

// Four doubles: an AVX register, or two SSE2 ones in the baseline build. The code below runs the
// same operations in the same order per lane whatever the width (vector_clones.h), so every
// build gives the same results. The sizes are template parameters: every loop below has a known
// trip count and is unrolled, and every lane it reads is known at compile time.
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

/// The update with H given by its columns, in chunks of four rows (lanes past R zero; the
/// position's columns are not read).
template <int D, int R>
__attribute__((always_inline)) inline void update(double* P, const V4 (&Hc)[D][(R + 3) / 4],
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
  // A = P H^T (D x R): column j = sum over c of P(:, c) H(j, c).
  V4 A[R][kQ];
  FREEINIT_UNROLL
  for (int j = 0; j < R; ++j) {
    FREEINIT_UNROLL
    for (int q = 0; q < kQ; ++q) A[j][q] = V4{0, 0, 0, 0};
    FREEINIT_UNROLL
    for (int c = 0; c < D; ++c) {
      if (!used(c)) continue;
      const double h = Hc[c][j / 4][j % 4];
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
  // The factorization is a chain of dependent operations: one division per column (its inverse
  // diagonal), multiplications elsewhere.
  double inv_diag[R];
  FREEINIT_UNROLL
  for (int j = 0; j < R; ++j) {
    double diag = S[j][j];
    FREEINIT_UNROLL
    for (int k = 0; k < j; ++k) diag -= S[j][k] * S[j][k];
    diag = std::sqrt(diag);
    inv_diag[j] = 1.0 / diag;
    FREEINIT_UNROLL
    for (int i = j + 1; i < R; ++i) {
      double v = S[i][j];
      FREEINIT_UNROLL
      for (int k = 0; k < j; ++k) v -= S[i][k] * S[j][k];
      S[i][j] = v * inv_diag[j];
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
    for (int q = 0; q < kQ; ++q) A[j][q] *= inv_diag[j];
    z[j] = zj * inv_diag[j];
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

template <int D, int R>
__attribute__((always_inline)) inline void updateFromH(double* P, const double* H,
                                                       const double* innovation, double* dx) {
  constexpr int kRq = (R + 3) / 4;
  V4 Hc[D][kRq];
  FREEINIT_UNROLL
  for (int c = 0; c < D; ++c) {
    FREEINIT_UNROLL
    for (int q = 0; q < kRq; ++q) load(H + c * R + 4 * q, rows(R, q), Hc[c][q]);
  }
  update<D, R>(P, Hc, innovation, dx);
}

/// The update by a node's Doppler rows: H = W G, the innovation -r0 - H dx.
template <int D>
__attribute__((always_inline)) inline void updateFromRows(double* P, const double* W,
                                                          const double* G, const double* r0,
                                                          double* dx) {
  constexpr int R = 9, kRq = 3;
  V4 Wc[R][kRq];  // W's columns
  FREEINIT_UNROLL
  for (int k = 0; k < R; ++k) {
    FREEINIT_UNROLL
    for (int q = 0; q < kRq; ++q) load(W + k * R + 4 * q, rows(R, q), Wc[k][q]);
  }
  // H(:, c) = sum over k of W(:, k) G(k, c); the innovation accumulated column by column.
  V4 Hc[D][kRq];
  V4 Hdx[kRq];
  FREEINIT_UNROLL
  for (int q = 0; q < kRq; ++q) Hdx[q] = V4{0, 0, 0, 0};
  FREEINIT_UNROLL
  for (int c = 0; c < D; ++c) {
    FREEINIT_UNROLL
    for (int q = 0; q < kRq; ++q) Hc[c][q] = V4{0, 0, 0, 0};
    if (!used(c)) continue;
    FREEINIT_UNROLL
    for (int k = 0; k < R; ++k) {
      const double g = G[c * R + k];
      FREEINIT_UNROLL
      for (int q = 0; q < kRq; ++q) Hc[c][q] += Wc[k][q] * g;
    }
    FREEINIT_UNROLL
    for (int q = 0; q < kRq; ++q) Hdx[q] += Hc[c][q] * dx[c];
  }
  double innovation[4 * kRq];
  FREEINIT_UNROLL
  for (int q = 0; q < kRq; ++q) {
    V4 r;
    load(r0 + 4 * q, rows(R, q), r);
    store(-r - Hdx[q], 4, innovation + 4 * q);
  }
  update<D, R>(P, Hc, innovation, dx);
}

/// The 4 x 4 blocks of a square matrix held as rows of chunks (in[r][q]: row r, columns 4q..4q+3)
/// transposed: out[c][q] holds column c, rows 4q..4q+3.
template <int kQ>
inline void transpose(const V4 (&in)[4 * kQ][kQ], V4 (&out)[4 * kQ][kQ]) {
  typedef std::int64_t I4 __attribute__((vector_size(32)));
  FREEINIT_UNROLL
  for (int rb = 0; rb < kQ; ++rb) {
    FREEINIT_UNROLL
    for (int cb = 0; cb < kQ; ++cb) {
      const V4 &a = in[4 * rb][cb], &b = in[4 * rb + 1][cb], &c = in[4 * rb + 2][cb],
               &d = in[4 * rb + 3][cb];
      const V4 t0 = __builtin_shuffle(a, b, I4{0, 4, 2, 6});
      const V4 t1 = __builtin_shuffle(a, b, I4{1, 5, 3, 7});
      const V4 t2 = __builtin_shuffle(c, d, I4{0, 4, 2, 6});
      const V4 t3 = __builtin_shuffle(c, d, I4{1, 5, 3, 7});
      out[4 * cb][rb] = __builtin_shuffle(t0, t2, I4{0, 1, 4, 5});
      out[4 * cb + 1][rb] = __builtin_shuffle(t1, t3, I4{0, 1, 4, 5});
      out[4 * cb + 2][rb] = __builtin_shuffle(t0, t2, I4{2, 3, 6, 7});
      out[4 * cb + 3][rb] = __builtin_shuffle(t1, t3, I4{2, 3, 6, 7});
    }
  }
}

/// F X for the rows of X (each a vector over the columns): row i of the result is
/// sum_k F(i, k) X(k, :), for the rows of the attitude, position and velocity; the other rows
/// are X's.
template <int kRows, int kQ>
inline void transitionTimes(const TransitionBlocks& F, const V4 (&X)[kRows][kQ],
                            V4 (&out)[kRows][kQ]) {
  constexpr int kTh = 0, kP = 3, kV = 6, kBg = 9, kBa = 12;
  auto e = [](const double* block, int i, int k) { return block[i + 3 * k]; };
  FREEINIT_UNROLL
  for (int q = 0; q < kQ; ++q) {
    FREEINIT_UNROLL
    for (int i = 0; i < 3; ++i) {
      V4 th = V4{0, 0, 0, 0};
      V4 p = X[kP + i][q] + X[kV + i][q] * F.tau;
      V4 v = X[kV + i][q];
      FREEINIT_UNROLL
      for (int k = 0; k < 3; ++k) {
        th += X[kTh + k][q] * e(F.th_th, i, k);
        p += X[kTh + k][q] * e(F.p_th, i, k);
        v += X[kTh + k][q] * e(F.v_th, i, k);
      }
      FREEINIT_UNROLL
      for (int k = 0; k < 3; ++k) {
        th += X[kBg + k][q] * e(F.th_bg, i, k);
        p += X[kBg + k][q] * e(F.p_bg, i, k);
        v += X[kBg + k][q] * e(F.v_bg, i, k);
      }
      FREEINIT_UNROLL
      for (int k = 0; k < 3; ++k) {
        p += X[kBa + k][q] * e(F.p_ba, i, k);
        v += X[kBa + k][q] * e(F.v_ba, i, k);
      }
      out[kTh + i][q] = th;
      out[kP + i][q] = p;
      out[kV + i][q] = v;
    }
    FREEINIT_UNROLL
    for (int i = 9; i < kRows; ++i) out[i][q] = X[i][q];
  }
}

template <int D>
__attribute__((always_inline)) inline void propagate(const TransitionBlocks& F,
                                                     const ProcessNoiseBlocks& Q, const double* P,
                                                     double* out) {
  constexpr int kQ = (D + 3) / 4;
  constexpr int kRows = 4 * kQ;  // padded with zero rows
  // P's rows (its columns: P is symmetric), then T = F P, then F T^T = F P F^T by rows.
  V4 X[kRows][kQ], Y[kRows][kQ];
  FREEINIT_UNROLL
  for (int r = 0; r < kRows; ++r) {
    FREEINIT_UNROLL
    for (int q = 0; q < kQ; ++q) {
      if (r < D)
        load(P + r * kLd + 4 * q, rows(D, q), X[r][q]);
      else
        X[r][q] = V4{0, 0, 0, 0};
    }
  }
  transitionTimes(F, X, Y);
  transpose(Y, X);
  transitionTimes(F, X, Y);
  // The mean of the product and its transpose: symmetric to the last bit.
  transpose(Y, X);
  if (D < kLd) std::memcpy(out, P, sizeof(double) * kLd * kLd);
  FREEINIT_UNROLL
  for (int c = 0; c < D; ++c) {
    FREEINIT_UNROLL
    for (int q = 0; q < kQ; ++q)
      store((X[c][q] + Y[c][q]) * 0.5, rows(D, q), out + c * kLd + 4 * q);
  }
  auto add = [out](int row, int col, double v) {
    for (int i = 0; i < 3; ++i) out[(col + i) * kLd + row + i] += v;
  };
  add(0, 0, Q.theta);
  add(3, 3, Q.pos);
  add(3, 6, Q.pos_vel);
  add(6, 3, Q.pos_vel);
  add(6, 6, Q.vel);
  add(9, 9, Q.bg);
  add(12, 12, Q.ba);
}

template <int D>
__attribute__((always_inline)) inline void choleskySolve(const double* A, double* b) {
  constexpr int kQ = (D + 3) / 4;
  // A's columns; column j becomes L's below the diagonal (lanes at and above it zero), its
  // diagonal kept apart as its inverse (one division per column in the chain of dependent
  // operations, multiplications elsewhere).
  V4 L[D][kQ];
  double inv_diag[D];
  FREEINIT_UNROLL
  for (int c = 0; c < D; ++c) {
    FREEINIT_UNROLL
    for (int q = 0; q < kQ; ++q) load(A + c * kLd + 4 * q, rows(D, q), L[c][q]);
  }
  FREEINIT_UNROLL
  for (int j = 0; j < D; ++j) {
    const double inv_d = 1.0 / std::sqrt(L[j][j / 4][j % 4]);
    inv_diag[j] = inv_d;
    FREEINIT_UNROLL
    for (int q = 0; q < kQ; ++q) {
      if (q < j / 4) {
        L[j][q] = V4{0, 0, 0, 0};
        continue;
      }
      L[j][q] *= inv_d;
      if (q == j / 4) {
        // A constant trip count, so that the annotation holds at every -O level.
        FREEINIT_UNROLL
        for (int l = 0; l < 4; ++l) {
          if (l <= j % 4) L[j][q][l] = 0.0;
        }
      }
    }
    // The columns right of j lose L(:, j) L(k, j) (their rows at and below k are read).
    FREEINIT_UNROLL
    for (int k = j + 1; k < D; ++k) {
      const double l = L[j][k / 4][k % 4];
      FREEINIT_UNROLL
      for (int q = k / 4; q < kQ; ++q) L[k][q] -= L[j][q] * l;
    }
  }
  // L y = b, then L^T x = y.
  V4 y[kQ];
  FREEINIT_UNROLL
  for (int q = 0; q < kQ; ++q) load(b + 4 * q, rows(D, q), y[q]);
  FREEINIT_UNROLL
  for (int j = 0; j < D; ++j) {
    const double yj = y[j / 4][j % 4] * inv_diag[j];
    y[j / 4][j % 4] = yj;
    FREEINIT_UNROLL
    for (int q = j / 4; q < kQ; ++q) y[q] -= L[j][q] * yj;
  }
  FREEINIT_UNROLL
  for (int j = D - 1; j >= 0; --j) {
    V4 dot = V4{0, 0, 0, 0};
    FREEINIT_UNROLL
    for (int q = j / 4; q < kQ; ++q) dot += L[j][q] * y[q];
    y[j / 4][j % 4] = (y[j / 4][j % 4] - ((dot[0] + dot[1]) + (dot[2] + dot[3]))) * inv_diag[j];
  }
  FREEINIT_UNROLL
  for (int q = 0; q < kQ; ++q) store(y[q], rows(D, q), b + 4 * q);
}

}  // namespace

// One function per size, each built for several instruction sets (vector_clones.h;
// target_clones does not apply to templates).
FREEINIT_VECTOR_CLONES
void kalmanUpdate15x6(double* P, const double* H, const double* innovation, double* dx) {
  updateFromH<15, 6>(P, H, innovation, dx);
}

FREEINIT_VECTOR_CLONES
void kalmanUpdate16x6(double* P, const double* H, const double* innovation, double* dx) {
  updateFromH<16, 6>(P, H, innovation, dx);
}

FREEINIT_VECTOR_CLONES
void kalmanUpdate19x6(double* P, const double* H, const double* innovation, double* dx) {
  updateFromH<19, 6>(P, H, innovation, dx);
}

template <>
void kalmanUpdateKernel<15, 6>(double* P, const double* H, const double* innovation, double* dx) {
  kalmanUpdate15x6(P, H, innovation, dx);
}
template <>
void kalmanUpdateKernel<16, 6>(double* P, const double* H, const double* innovation, double* dx) {
  kalmanUpdate16x6(P, H, innovation, dx);
}
template <>
void kalmanUpdateKernel<19, 6>(double* P, const double* H, const double* innovation, double* dx) {
  kalmanUpdate19x6(P, H, innovation, dx);
}

}  // namespace freeinit::detail

namespace freeinit::detail {

FREEINIT_VECTOR_CLONES
void dopplerUpdate15(double* P, const double* W, const double* G, const double* r0, double* dx) {
  updateFromRows<15>(P, W, G, r0, dx);
}
FREEINIT_VECTOR_CLONES
void dopplerUpdate16(double* P, const double* W, const double* G, const double* r0, double* dx) {
  updateFromRows<16>(P, W, G, r0, dx);
}
FREEINIT_VECTOR_CLONES
void dopplerUpdate19(double* P, const double* W, const double* G, const double* r0, double* dx) {
  updateFromRows<19>(P, W, G, r0, dx);
}
template <>
void dopplerUpdateKernel<15>(double* P, const double* W, const double* G, const double* r0,
                             double* dx) {
  dopplerUpdate15(P, W, G, r0, dx);
}
template <>
void dopplerUpdateKernel<16>(double* P, const double* W, const double* G, const double* r0,
                             double* dx) {
  dopplerUpdate16(P, W, G, r0, dx);
}
template <>
void dopplerUpdateKernel<19>(double* P, const double* W, const double* G, const double* r0,
                             double* dx) {
  dopplerUpdate19(P, W, G, r0, dx);
}

FREEINIT_VECTOR_CLONES
void propagateCovariance15(const TransitionBlocks& F, const ProcessNoiseBlocks& Q, const double* P,
                           double* out) {
  propagate<15>(F, Q, P, out);
}
FREEINIT_VECTOR_CLONES
void propagateCovariance16(const TransitionBlocks& F, const ProcessNoiseBlocks& Q, const double* P,
                           double* out) {
  propagate<16>(F, Q, P, out);
}
FREEINIT_VECTOR_CLONES
void propagateCovariance19(const TransitionBlocks& F, const ProcessNoiseBlocks& Q, const double* P,
                           double* out) {
  propagate<19>(F, Q, P, out);
}
FREEINIT_VECTOR_CLONES
void choleskySolve15(const double* A, double* b) { choleskySolve<15>(A, b); }
FREEINIT_VECTOR_CLONES
void choleskySolve16(const double* A, double* b) { choleskySolve<16>(A, b); }
FREEINIT_VECTOR_CLONES
void choleskySolve19(const double* A, double* b) { choleskySolve<19>(A, b); }

template <>
void propagateCovarianceKernel<15>(const TransitionBlocks& F, const ProcessNoiseBlocks& Q,
                                   const double* P, double* out) {
  propagateCovariance15(F, Q, P, out);
}
template <>
void propagateCovarianceKernel<16>(const TransitionBlocks& F, const ProcessNoiseBlocks& Q,
                                   const double* P, double* out) {
  propagateCovariance16(F, Q, P, out);
}
template <>
void propagateCovarianceKernel<19>(const TransitionBlocks& F, const ProcessNoiseBlocks& Q,
                                   const double* P, double* out) {
  propagateCovariance19(F, Q, P, out);
}
template <>
void choleskySolveKernel<15>(const double* A, double* b) {
  choleskySolve15(A, b);
}
template <>
void choleskySolveKernel<16>(const double* A, double* b) {
  choleskySolve16(A, b);
}
template <>
void choleskySolveKernel<19>(const double* A, double* b) {
  choleskySolve19(A, b);
}

}  // namespace freeinit::detail

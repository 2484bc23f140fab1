#include "kalman_kernel.h"

#include <cmath>
#include <cstring>

namespace freeinit::detail {
namespace {

// Four doubles: an AVX register, or two SSE2 ones in the baseline build. The vector code below
// runs the same operations in the same order per lane whatever the width (no fused multiply-add
// in either), so both builds give the same results; built for both, chosen at load time.
typedef double V4 __attribute__((vector_size(32)));
constexpr int kStateChunks = kKalmanMaxStates / 4;
constexpr int kRowChunks = kKalmanMaxRows / 4;
static_assert(kKalmanMaxStates % 4 == 0 && kKalmanMaxRows % 4 == 0);

/// n (<= 4 * chunks) values into chunks of four, zero-padded.
template <int kChunks>
void load(const double* v, int n, V4 (&out)[kChunks]) {
  double padded[4 * kChunks] = {};
  std::memcpy(padded, v, static_cast<std::size_t>(n) * sizeof(double));
  std::memcpy(out, padded, sizeof out);
}

}  // namespace

#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void kalmanUpdateKernel(int d, int r, double* P, int ld, const double* H, const double* innovation,
                        double* dx, int skip_begin, int skip_end) {
  const int nq = (d + 3) / 4, nrq = (r + 3) / 4;
  auto used = [skip_begin, skip_end](int c) { return c < skip_begin || c >= skip_end; };
  // P and H by columns, in chunks of four rows.
  V4 Pc[kKalmanMaxStates][kStateChunks], Hc[kKalmanMaxStates][kRowChunks];
  for (int c = 0; c < d; ++c) {
    load(P + static_cast<std::ptrdiff_t>(c) * ld, d, Pc[c]);
    load(H + static_cast<std::ptrdiff_t>(c) * r, r, Hc[c]);
  }
  // A = P H^T (d x r), column j = sum over c of P(:, c) H(j, c).
  V4 A[kKalmanMaxRows][kStateChunks];
  for (int j = 0; j < r; ++j) {
    for (int q = 0; q < nq; ++q) A[j][q] = V4{0, 0, 0, 0};
    for (int c = 0; c < d; ++c) {
      if (!used(c)) continue;
      const double h = H[c * r + j];
      for (int q = 0; q < nq; ++q) A[j][q] += Pc[c][q] * h;
    }
  }
  // S = H A + I (r x r), column j = sum over c of H(:, c) A(c, j); then S = L L^T, L in the
  // lower triangle (S >= I: the factorization cannot fail).
  double S[kKalmanMaxRows][kKalmanMaxRows];  // S[i][j]: row i, column j
  for (int j = 0; j < r; ++j) {
    V4 s[kRowChunks];
    for (int q = 0; q < nrq; ++q) s[q] = V4{0, 0, 0, 0};
    for (int c = 0; c < d; ++c) {
      if (!used(c)) continue;
      const double a = A[j][c / 4][c % 4];
      for (int q = 0; q < nrq; ++q) s[q] += Hc[c][q] * a;
    }
    for (int i = 0; i < r; ++i) S[i][j] = s[i / 4][i % 4];
    S[j][j] += 1.0;
  }
  for (int j = 0; j < r; ++j) {
    double diag = S[j][j];
    for (int k = 0; k < j; ++k) diag -= S[j][k] * S[j][k];
    diag = std::sqrt(diag);
    S[j][j] = diag;
    for (int i = j + 1; i < r; ++i) {
      double v = S[i][j];
      for (int k = 0; k < j; ++k) v -= S[i][k] * S[j][k];
      S[i][j] = v / diag;
    }
  }
  // Y = A L^-T (in A), z = L^-1 innovation.
  double z[kKalmanMaxRows];
  for (int j = 0; j < r; ++j) {
    double zj = innovation[j];
    for (int i = 0; i < j; ++i) {
      const double l = S[j][i];
      for (int q = 0; q < nq; ++q) A[j][q] -= A[i][q] * l;
      zj -= l * z[i];
    }
    for (int q = 0; q < nq; ++q) A[j][q] /= S[j][j];
    z[j] = zj / S[j][j];
  }
  // dx += Y z; P -= Y Y^T, element (i, c) summed over j in the same order as (c, i).
  V4 step[kStateChunks];
  for (int q = 0; q < nq; ++q) {
    step[q] = V4{0, 0, 0, 0};
    for (int j = 0; j < r; ++j) step[q] += A[j][q] * z[j];
  }
  double padded[4 * kStateChunks];
  std::memcpy(padded, step, sizeof step);
  for (int i = 0; i < d; ++i) dx[i] += padded[i];
  for (int c = 0; c < d; ++c) {
    for (int q = 0; q < nq; ++q) {
      V4 yy = V4{0, 0, 0, 0};
      for (int j = 0; j < r; ++j) yy += A[j][q] * A[j][c / 4][c % 4];
      Pc[c][q] -= yy;
    }
    std::memcpy(padded, Pc[c], sizeof Pc[c]);
    std::memcpy(P + static_cast<std::ptrdiff_t>(c) * ld, padded,
                static_cast<std::size_t>(d) * sizeof(double));
  }
}

}  // namespace freeinit::detail

// The code shape in which g++ 12.2 lost stores (docs/architecture.md, docs/reliability.md):
// a local covariance whose LOWER triangle is written through raw pointers (the first-round
// lower_minus_product of core/numerics.hpp, commit 63871f6), then mirrored by a plain loop
// (the first-round symmetrize), then checked and copied out, as ekf::update did. No Eigen: a
// plain struct of N*N doubles, column-major, so that every access is a double lvalue and no
// aliasing question can arise. Included twice, into namespaces compiled at -O0 and -O2
// (store_o0.cpp, store_o2.cpp), by the test that compares them bit for bit.
#pragma once

#include <cmath>
#include <cstddef>

template <int N>
struct Mat {
  double a[N * N];
  double& operator()(int i, int j) { return a[j * N + i]; }
  double operator()(int i, int j) const { return a[j * N + i]; }
};

/// out = P - A B' on the lower triangle (A, B: N x K, column-major), two rows at a time.
template <int N, int K>
void lower_minus_product(const Mat<N>& P, const double* A, const double* B, Mat<N>& out) {
  for (int j = 0; j < N; ++j) {
    double b[K];
    for (int k = 0; k < K; ++k) b[k] = B[k * N + j];
    const double* p = P.a + j * N;
    double* o = out.a + j * N;
    int i = j;
    for (; i + 1 < N; i += 2) {
      double s0 = p[i], s1 = p[i + 1];
      for (int k = 0; k < K; ++k) {
        s0 -= A[k * N + i] * b[k];
        s1 -= A[k * N + i + 1] * b[k];
      }
      o[i] = s0;
      o[i + 1] = s1;
    }
    if (i < N) {
      double s = p[i];
      for (int k = 0; k < K; ++k) s -= A[k * N + i] * b[k];
      o[i] = s;
    }
  }
}

/// The plain-loop mirror that was miscompiled in the demo binary.
template <int N>
void symmetrize_loop(Mat<N>& P) {
  for (int j = 1; j < N; ++j)
    for (int i = 0; i < j; ++i) P(i, j) = P(j, i);
}

/// One scalar-measurement Joseph update, expanded as the library did: with h the measurement
/// row and r its variance, PHt = P h', s = h P h' + r, K = PHt / s, and
/// P+ = P - [K, K s - PHt] [PHt, -K]'. The result goes to a local that is mirrored, checked
/// and copied out; false (and P unchanged) when s is not positive or the result not finite.
template <int N>
bool scalar_update(Mat<N>& P, const double* h, double r) {
  double pht[N], k[N];
  double s = r;
  for (int i = 0; i < N; ++i) {
    double acc = 0.0;
    for (int j = 0; j < N; ++j) acc += P(i, j) * h[j];
    pht[i] = acc;
  }
  for (int i = 0; i < N; ++i) s += h[i] * pht[i];
  if (!(s > 0.0)) return false;
  for (int i = 0; i < N; ++i) k[i] = pht[i] / s;
  double left[2 * N], right[2 * N];
  for (int i = 0; i < N; ++i) {
    left[i] = k[i];
    left[N + i] = k[i] * s - pht[i];
    right[i] = pht[i];
    right[N + i] = -k[i];
  }
  Mat<N> out;  // deliberately uninitialised, as in the library: the loop writes every entry
  lower_minus_product<N, 2>(P, left, right, out);
  symmetrize_loop(out);
  for (double v : out.a)
    if (!std::isfinite(v)) return false;
  P = out;
  return true;
}

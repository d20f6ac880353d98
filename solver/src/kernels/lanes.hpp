#pragma once
// The arithmetic of the stress pass, written once for one tet (T = double) and for kLanes tets
// side by side (T = Pack, one tet per lane). Pack is a GCC/Clang vector type: every operator on
// it is an element-wise SIMD instruction on the target (one AVX2 register with -march=native;
// two SSE2 halves in a portable build), so the laws' formulas, written as templates over T, are
// vectorised by construction rather than by the auto-vectoriser's judgement. A comparison of
// packs gives a lane mask and `mask ? a : b` selects per lane, which is how a law writes a
// branch that must hold for both (hgo's fibre switch).
#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

namespace tactus::solver::lanes {

inline constexpr int kLanes = 4;
typedef double Pack __attribute__((vector_size(kLanes * sizeof(double))));
typedef std::int64_t PackMask __attribute__((vector_size(kLanes * sizeof(double))));
typedef std::uint64_t PackBits __attribute__((vector_size(kLanes * sizeof(double))));

// A 3x3 matrix of T, row-major: M(i, j).
template <class T>
struct M3 {
  T a[9];
  T& operator()(int i, int j) { return a[3 * i + j]; }
  const T& operator()(int i, int j) const { return a[3 * i + j]; }
};
template <class T>
struct V3 {
  T a[3];
  T& operator[](int i) { return a[i]; }
  const T& operator[](int i) const { return a[i]; }
};

template <class T>
[[gnu::always_inline]] inline M3<T> operator+(const M3<T>& x, const M3<T>& y) {
  M3<T> r;
  for (int k = 0; k < 9; ++k) r.a[k] = x.a[k] + y.a[k];
  return r;
}
template <class T>
[[gnu::always_inline]] inline M3<T> operator-(const M3<T>& x, const M3<T>& y) {
  M3<T> r;
  for (int k = 0; k < 9; ++k) r.a[k] = x.a[k] - y.a[k];
  return r;
}
template <class T>
[[gnu::always_inline]] inline M3<T>& operator+=(M3<T>& x, const M3<T>& y) {
  for (int k = 0; k < 9; ++k) x.a[k] += y.a[k];
  return x;
}
template <class T, class S>
[[gnu::always_inline]] inline M3<T> operator*(const S& s, const M3<T>& x) {
  M3<T> r;
  for (int k = 0; k < 9; ++k) r.a[k] = s * x.a[k];
  return r;
}
// x y (matrix product)
template <class T>
[[gnu::always_inline]] inline M3<T> operator*(const M3<T>& x, const M3<T>& y) {
  M3<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = x(i, 0) * y(0, j) + x(i, 1) * y(1, j) + x(i, 2) * y(2, j);
  return r;
}
// x^T y
template <class T>
[[gnu::always_inline]] inline M3<T> transpose_times(const M3<T>& x, const M3<T>& y) {
  M3<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = x(0, i) * y(0, j) + x(1, i) * y(1, j) + x(2, i) * y(2, j);
  return r;
}
// x a, for a vector a of any lane type (a law's constant fibre, or a per-lane one)
template <class T, class S>
[[gnu::always_inline]] inline V3<T> operator*(const M3<T>& x, const V3<S>& a) {
  V3<T> r;
  for (int i = 0; i < 3; ++i) r[i] = x(i, 0) * a[0] + x(i, 1) * a[1] + x(i, 2) * a[2];
  return r;
}
// x (x) y
template <class T, class S>
[[gnu::always_inline]] inline M3<T> outer(const V3<T>& x, const V3<S>& y) {
  M3<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = x[i] * y[j];
  return r;
}
template <class T>
[[gnu::always_inline]] inline T trace(const M3<T>& x) {
  return x.a[0] + x.a[4] + x.a[8];
}
template <class T>
[[gnu::always_inline]] inline T squared_norm(const M3<T>& x) {
  T s = x.a[0] * x.a[0];
  for (int k = 1; k < 9; ++k) s += x.a[k] * x.a[k];
  return s;
}
template <class T>
[[gnu::always_inline]] inline T squared_norm(const V3<T>& x) {
  return x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
}
// A value of T with every lane v.
template <class T>
[[gnu::always_inline]] inline T splat(double v) {
  if constexpr (std::is_same_v<T, Pack>)
    return Pack{} + v;
  else
    return v;
}
template <class T>
[[gnu::always_inline]] inline M3<T> identity_times(const T& s) {
  M3<T> r;
  for (int k = 0; k < 9; ++k) r.a[k] = splat<T>(0.0);
  r.a[0] = r.a[4] = r.a[8] = s;
  return r;
}
// Lane access: a double is its own single lane.
[[gnu::always_inline]] inline double lane(double x, int) { return x; }
[[gnu::always_inline]] inline double lane(const Pack& x, int l) { return x[l]; }
template <class T>
inline constexpr int lanes_of = std::is_same_v<T, Pack> ? kLanes : 1;
// The T whose lane l is value(l).
template <class T, class Fn>
[[gnu::always_inline]] inline T make_lanes(Fn value) {
  if constexpr (std::is_same_v<T, Pack>) {
    double v[kLanes];
    for (int l = 0; l < kLanes; ++l) v[l] = value(l);
    Pack r;
    std::memcpy(&r, v, sizeof r);
    return r;
  } else {
    return value(0);
  }
}

// x^{-1/3} for x > 0, to 1e-15 relative: a bit-level first guess refined by four division-free
// Newton steps on 1/y^3 = x, y <- y (4 - x y^3) / 3 (libm's cbrt, with its frexp/scalbn, took a
// quarter of a neo-Hookean update). The same operations for double and, lane by lane, for Pack.
template <class T>
[[gnu::always_inline]] inline T inv_cbrt(const T& x) {
  using Bits = std::conditional_t<std::is_same_v<T, Pack>, PackBits, std::uint64_t>;
  Bits i;
  std::memcpy(&i, &x, sizeof i);
  i = 0x553ef0ff289dd796ULL - i / 3;
  T y;
  std::memcpy(&y, &i, sizeof y);
  for (int k = 0; k < 4; ++k) y = y * (4.0 - x * y * y * y) * (1.0 / 3.0);
  return y;
}

// e^x: libm's for one lane; for a pack, Cody-Waite reduction x = k ln2 + r, |r| <= ln2 / 2, the
// Taylor polynomial of degree 12 (truncation 1.7e-16 relative) in Horner form, and 2^k put into
// exponent bits (as 2^(k/2) 2^(k - k/2), so that k = 1024 and subnormal results stay right): every
// step a SIMD instruction, within a few ulp of libm (tested). hgo's fibres call it for every tet.
[[gnu::always_inline]] inline double exp_of(double x) { return std::exp(x); }
[[gnu::always_inline]] inline Pack exp_of(const Pack& x) {
  constexpr double kLog2e = 1.4426950408889634074, kLn2Hi = 6.93147180369123816490e-01, kLn2Lo = 1.90821492927058770002e-10;
  constexpr double kRound = 6755399441055744.0;  // 1.5 * 2^52: adding it rounds to an integer in the low bits
  constexpr double kLogMax = 709.782712893384, kLogMin = -745.2;
  const Pack clamped = x > 710.0 ? Pack{} + 710.0 : (x < -746.0 ? Pack{} - 746.0 : x);
  const Pack shifted = clamped * kLog2e + kRound;
  const Pack k = shifted - kRound;
  const Pack r = (clamped - k * kLn2Hi) - k * kLn2Lo;
  Pack p = Pack{} + 1.0 / 479001600.0;  // 1/12!
  constexpr double kInverseFactorials[12] = {1.0 / 39916800.0, 1.0 / 3628800.0, 1.0 / 362880.0, 1.0 / 40320.0, 1.0 / 5040.0, 1.0 / 720.0,
                                             1.0 / 120.0,      1.0 / 24.0,      1.0 / 6.0,      0.5,           1.0,          1.0};
  for (double c : kInverseFactorials) p = p * r + c;
  PackMask ki;
  std::memcpy(&ki, &shifted, sizeof ki);
  std::int64_t round_bits;
  std::memcpy(&round_bits, &kRound, sizeof round_bits);
  ki -= round_bits;  // k as an integer
  const PackMask k1 = ki >> 1, k2 = ki - k1;
  const PackMask bits1 = (k1 + 1023) << 52, bits2 = (k2 + 1023) << 52;
  Pack scale1, scale2;
  std::memcpy(&scale1, &bits1, sizeof scale1);
  std::memcpy(&scale2, &bits2, sizeof scale2);
  const Pack e = (p * scale1) * scale2;
  return x > kLogMax ? Pack{} + std::numeric_limits<double>::infinity() : (x < kLogMin ? Pack{} : e);
}
[[gnu::always_inline]] inline double sqrt_of(double x) { return std::sqrt(x); }
// One vsqrtpd where AVX is on (correctly rounded, the same bits as std::sqrt per lane): lane by
// lane, std::sqrt is a scalar sqrt and an errno check each.
[[gnu::always_inline]] inline Pack sqrt_of(const Pack& x) {
#if defined(__AVX__)
  static_assert(sizeof(Pack) == sizeof(__m256d));
  return reinterpret_cast<Pack>(_mm256_sqrt_pd(reinterpret_cast<__m256d>(x)));
#else
  return make_lanes<Pack>([&](int l) { return std::sqrt(x[l]); });
#endif
}

// |x|, and the lane-wise larger and smaller of two (a comparison's mask selects; no NaN here).
[[gnu::always_inline]] inline double abs_of(double x) { return std::abs(x); }
[[gnu::always_inline]] inline Pack abs_of(const Pack& x) { return x < 0 ? -x : x; }
template <class T>
[[gnu::always_inline]] inline T max_of(const T& x, const T& y) {
  if constexpr (std::is_same_v<T, double>)
    return std::max(x, y);
  else
    return x > y ? x : y;
}
template <class T>
[[gnu::always_inline]] inline T min_of(const T& x, const T& y) {
  if constexpr (std::is_same_v<T, double>)
    return std::min(x, y);
  else
    return x < y ? x : y;
}

}  // namespace tactus::solver::lanes

#pragma once
// The 3-vector of tactus's data between stages (points, directions, velocities in meshes, scenarios
// and results: std::array<double, 3>, as in TetMesh) and its few operations, shared by every stage.
// Inside the solver's algebra Eigen's Vec3d is used (rigid bodies, contact frames), and the SIMD
// kernels have their own lane vectors (lanes::V3); this one is for the data they exchange.
#include <array>
#include <cmath>

namespace tactus {

using Vec3 = std::array<double, 3>;

inline Vec3 operator+(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 operator-(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 operator*(double s, const Vec3& a) { return {s * a[0], s * a[1], s * a[2]}; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
// The vector from b to a, for coordinates stored 3 per node in flat arrays.
inline Vec3 sub(const double* a, const double* b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 load3(const double* a) { return {a[0], a[1], a[2]}; }

}  // namespace tactus

// SPDX-License-Identifier: BSD-3-Clause
// A 3-vector of doubles as a plain std::array (so .data() passes it to the x y z triple
// interfaces, e.g. KdTree) and the few operations the surface reconstruction and its remesher
// use. The operators are declared in dp::support, which argument-dependent lookup does not search
// for std::array: code outside dp::support brings them in with using-declarations.
#pragma once

#include <array>
#include <cmath>

namespace dp::support
{

using Vec3 = std::array<double, 3>;

inline Vec3 operator+(const Vec3& a, const Vec3& b)
{
  return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
inline Vec3 operator-(const Vec3& a, const Vec3& b)
{
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
inline Vec3 operator*(double s, const Vec3& a)
{
  return {s * a[0], s * a[1], s * a[2]};
}
inline double dot(const Vec3& a, const Vec3& b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline Vec3 cross(const Vec3& a, const Vec3& b)
{
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Vec3& a)
{
  return std::sqrt(dot(a, a));
}

} // namespace dp::support

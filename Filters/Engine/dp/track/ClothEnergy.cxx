// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/ClothEnergy.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace dp
{
namespace
{
struct V3
{
  double x, y, z;
};
inline V3 at(const double* p, std::int64_t i)
{
  return {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
}
inline V3 operator-(V3 a, V3 b)
{
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline V3 operator+(V3 a, V3 b)
{
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline V3 operator*(double s, V3 a)
{
  return {s * a.x, s * a.y, s * a.z};
}
inline double dot(V3 a, V3 b)
{
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline V3 cross(V3 a, V3 b)
{
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(V3 a)
{
  return std::sqrt(dot(a, a));
}
inline void add(double* g, std::int64_t i, V3 v)
{
  g[3 * i] += v.x;
  g[3 * i + 1] += v.y;
  g[3 * i + 2] += v.z;
}

// Angle at corner a of triangle (a, b, c), and its gradient with respect to b and c
// (the gradient for a is minus their sum). Returns false when the corner is degenerate.
bool cornerAngle(V3 a, V3 b, V3 c, double& angle, V3* gb, V3* gc)
{
  const V3 u = b - a, v = c - a;
  const double lu = norm(u), lv = norm(v);
  const V3 n = cross(u, v);
  const double s = norm(n);
  angle = std::atan2(s, dot(u, v));
  if (!gb)
    return true;
  if (lu == 0 || lv == 0 || s <= 1e-300)
    return false;
  // d(angle)/db is perpendicular to u, in the plane, pointing away from v, of size 1/|u|.
  const V3 towardV = (1.0 / (s * lu)) * cross(n, u); // unit, perpendicular to u, toward v
  const V3 towardU = (1.0 / (s * lv)) * cross(v, n); // unit, perpendicular to v, toward u
  *gb = (-1.0 / lu) * towardV;
  *gc = (-1.0 / lv) * towardU;
  return true;
}

// cos of the angle between the normals of triangles (a, b, c) and (b, a, d), and its gradient
// with respect to the four vertices. Returns false when a triangle is degenerate.
bool hingeCos(V3 a, V3 b, V3 c, V3 d, double& cosine, V3* g)
{
  const V3 e1 = b - a, e2 = c - a; // N1 = e1 x e2
  const V3 f1 = a - b, f2 = d - b; // N2 = f1 x f2
  const V3 n1 = cross(e1, e2), n2 = cross(f1, f2);
  const double l1 = norm(n1), l2 = norm(n2);
  if (l1 <= 1e-300 || l2 <= 1e-300)
  {
    cosine = 1.0;
    return false;
  }
  const V3 u1 = (1.0 / l1) * n1, u2 = (1.0 / l2) * n2;
  cosine = dot(u1, u2);
  if (!g)
    return true;
  // dc/dN1 = (u2 - c u1) / |N1|, dc/dN2 = (u1 - c u2) / |N2|; N = e x f gives
  // dc/de = f x (dc/dN), dc/df = (dc/dN) x e.
  const V3 gN1 = (1.0 / l1) * (u2 - cosine * u1);
  const V3 gN2 = (1.0 / l2) * (u1 - cosine * u2);
  const V3 ge1 = cross(e2, gN1), ge2 = cross(gN1, e1);
  const V3 gf1 = cross(f2, gN2), gf2 = cross(gN2, f1);
  // e1 = b - a, e2 = c - a, f1 = a - b, f2 = d - b
  g[0] = (-1.0 * (ge1 + ge2)) + gf1; // a
  g[1] = ge1 + (-1.0 * (gf1 + gf2)); // b
  g[2] = ge2;                        // c
  g[3] = gf2;                        // d
  return true;
}

// Fills one term after another (a single ClothTerm, reused) and hands each to the visitor.
struct TermVisitor
{
  const std::function<void(const ClothTerm&)>& visit;
  ClothTerm term;

  // Vertex k of the term and the residual's gradient with respect to it.
  void put(int k, std::int64_t vertex, V3 gradient)
  {
    term.vertex[k] = vertex;
    term.gradient[k][0] = gradient.x;
    term.gradient[k][1] = gradient.y;
    term.gradient[k][2] = gradient.z;
  }
  // The term with stiffness k (its residual set) is complete: visit it.
  void finish(double k)
  {
    term.weight = k;
    term.energy = 0.5 * k * term.residual * term.residual;
    visit(term);
  }
};

// Stretch: r = (l - l0) / L per edge, stiffness k times the edge's scale (if any).
void visitStretchTerms(const double* x, const TriangleMesh& mesh,
                       const std::vector<double>& restLength, double L, double k,
                       const std::vector<double>& scale, TermVisitor& out)
{
  out.term.count = 2;
  const auto& edges = mesh.edges();
  for (std::size_t e = 0; e < edges.size(); ++e)
  {
    const V3 d = at(x, edges[e][1]) - at(x, edges[e][0]);
    const double l = norm(d);
    out.term.residual = (l - restLength[e]) / L;
    const V3 u = l > 0 ? (1.0 / (l * L)) * d : V3{0, 0, 0};
    out.put(0, edges[e][1], u);
    out.put(1, edges[e][0], -1.0 * u);
    out.finish(scale.empty() ? k : k * scale[e]);
  }
}

// Shear: r = theta - theta0 at each triangle corner, stiffness k.
void visitShearTerms(const double* x, const TriangleMesh& mesh,
                     const std::vector<double>& restAngle, double k, TermVisitor& out)
{
  out.term.count = 3;
  const auto& tris = mesh.triangles();
  for (std::size_t t = 0; t < mesh.numberOfTriangles(); ++t)
    for (int c = 0; c < 3; ++c)
    {
      const std::int64_t ia = tris[3 * t + c], ib = tris[3 * t + (c + 1) % 3],
                         ic = tris[3 * t + (c + 2) % 3];
      double angle = 0;
      V3 gb{0, 0, 0}, gc{0, 0, 0};
      if (!cornerAngle(at(x, ia), at(x, ib), at(x, ic), angle, &gb, &gc))
        gb = gc = V3{0, 0, 0};
      out.term.residual = angle - restAngle[3 * t + c];
      out.put(0, ib, gb);
      out.put(1, ic, gc);
      out.put(2, ia, -1.0 * (gb + gc));
      out.finish(k);
    }
}

// Bend: r = cos(phi) - cos(phi0) at each hinge, stiffness k times its area share (hingeWeight)
// and its scale (if any).
void visitBendTerms(const double* x, const TriangleMesh& mesh,
                    const std::vector<double>& restCosine, double k,
                    const std::vector<double>& hingeWeight, const std::vector<double>& scale,
                    TermVisitor& out)
{
  out.term.count = 4;
  const auto& hinges = mesh.hinges();
  for (std::size_t h = 0; h < hinges.size(); ++h)
  {
    const auto& v = hinges[h];
    double cosine = 1;
    V3 gh[4] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    if (!hingeCos(at(x, v[0]), at(x, v[1]), at(x, v[2]), at(x, v[3]), cosine, gh))
      for (V3& gv : gh)
        gv = V3{0, 0, 0};
    out.term.residual = cosine - restCosine[h];
    for (int j = 0; j < 4; ++j)
      out.put(j, v[j], gh[j]);
    out.finish(k * hingeWeight[h] * (scale.empty() ? 1.0 : scale[h]));
  }
}
} // namespace

ClothEnergy::ClothEnergy(const TriangleMesh& mesh, const double* rest, const ClothParameters& k)
    : Mesh(&mesh), K(k)
{
  if (k.stretch < 0 || k.shear < 0 || k.bend < 0 || !std::isfinite(k.stretch + k.shear + k.bend))
    throw std::invalid_argument("cloth stiffnesses must be non-negative numbers");
  const double area = mesh.totalArea(rest);
  if (!(area > 0) || !std::isfinite(area))
    throw std::invalid_argument("the template mesh has no area");
  L = std::sqrt(area);
  // A (nearly) degenerate rest triangle makes its corner angles' gradients explode (they go as
  // 1 / edge length): refuse it by name rather than track with a matrix of 1e20s.
  const auto& tris = mesh.triangles();
  const double tiny = 1e-12 * area / static_cast<double>(mesh.numberOfTriangles());
  for (std::size_t t = 0; t < mesh.numberOfTriangles(); ++t)
  {
    const V3 a = at(rest, tris[3 * t]), b = at(rest, tris[3 * t + 1]),
             c = at(rest, tris[3 * t + 2]);
    const double triangleArea = 0.5 * norm(cross(b - a, c - a));
    if (!(triangleArea > tiny))
      throw std::invalid_argument(
          "the template mesh has a degenerate triangle: triangle " + std::to_string(t) +
          " (vertices " + std::to_string(tris[3 * t]) + ", " + std::to_string(tris[3 * t + 1]) +
          ", " + std::to_string(tris[3 * t + 2]) + ") has " +
          (triangleArea > 0 ? "an area of " + std::to_string(triangleArea / area) + " of the mesh's"
                            : std::string("no area")));
  }
  Rest = restStateOf(rest);
  std::vector<double> vertexArea = mesh.vertexAreas(rest);
  for (const auto& h : mesh.hinges())
  {
    const double a1 =
        0.5 * norm(cross(at(rest, h[1]) - at(rest, h[0]), at(rest, h[2]) - at(rest, h[0])));
    const double a2 =
        0.5 * norm(cross(at(rest, h[0]) - at(rest, h[1]), at(rest, h[3]) - at(rest, h[1])));
    HingeWeight.push_back((a1 + a2) / (3.0 * area));
  }
  Mass.resize(vertexArea.size());
  for (std::size_t v = 0; v < vertexArea.size(); ++v)
    Mass[v] = vertexArea[v] / area;
}

ClothRestState ClothEnergy::restStateOf(const double* x) const
{
  const TriangleMesh& mesh = *Mesh;
  ClothRestState rest;
  rest.length.reserve(mesh.edges().size());
  for (const auto& e : mesh.edges())
    rest.length.push_back(norm(at(x, e[1]) - at(x, e[0])));
  const auto& tris = mesh.triangles();
  rest.angle.reserve(tris.size());
  for (std::size_t t = 0; t < mesh.numberOfTriangles(); ++t)
    for (int k3 = 0; k3 < 3; ++k3)
    {
      double angle = 0;
      cornerAngle(at(x, tris[3 * t + k3]), at(x, tris[3 * t + (k3 + 1) % 3]),
                  at(x, tris[3 * t + (k3 + 2) % 3]), angle, nullptr, nullptr);
      rest.angle.push_back(angle);
    }
  rest.cosine.reserve(mesh.hinges().size());
  for (const auto& h : mesh.hinges())
  {
    double cosine = 1;
    hingeCos(at(x, h[0]), at(x, h[1]), at(x, h[2]), at(x, h[3]), cosine, nullptr);
    rest.cosine.push_back(cosine);
  }
  return rest;
}

void ClothEnergy::setRestState(ClothRestState rest)
{
  if (rest.length.size() != Rest.length.size() || rest.angle.size() != Rest.angle.size() ||
      rest.cosine.size() != Rest.cosine.size())
    throw std::invalid_argument("a rest state of another mesh");
  Rest = std::move(rest);
}

void ClothEnergy::setStiffnessScales(std::vector<double> edgeStretch, std::vector<double> hingeBend)
{
  auto check = [](const std::vector<double>& scales, std::size_t size, const char* what)
  {
    if (!scales.empty() && scales.size() != size)
      throw std::invalid_argument(std::string("stiffness scales: ") +
                                  std::to_string(scales.size()) + " for " + std::to_string(size) +
                                  " " + what);
    for (const double s : scales)
      if (!(s >= 0) || !std::isfinite(s))
        throw std::invalid_argument("stiffness scales must be non-negative numbers");
  };
  check(edgeStretch, Mesh->edges().size(), "edges");
  check(hingeBend, Mesh->hinges().size(), "hinges");
  StretchScale = std::move(edgeStretch);
  BendScale = std::move(hingeBend);
}

ClothRestState ClothRestState::blend(const ClothRestState& a, const ClothRestState& b, double t)
{
  ClothRestState out = a;
  auto mix = [t](std::vector<double>& x, const std::vector<double>& y)
  {
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] += t * (y[i] - x[i]);
  };
  mix(out.length, b.length);
  mix(out.angle, b.angle);
  mix(out.cosine, b.cosine);
  return out;
}

double ClothEnergy::value(const double* x) const
{
  return addGradient(x, nullptr);
}

double ClothEnergy::addGradient(const double* x, double* g) const
{
  double energy = 0;
  forEachTerm(x,
              [&](const ClothTerm& t)
              {
                energy += t.energy;
                if (g)
                  for (int k = 0; k < t.count; ++k)
                    for (int c = 0; c < 3; ++c)
                      g[3 * t.vertex[k] + c] += t.weight * t.residual * t.gradient[k][c];
              });
  return energy;
}

void ClothEnergy::forEachTerm(const double* x,
                              const std::function<void(const ClothTerm&)>& visit) const
{
  TermVisitor out{visit, ClothTerm{}};
  if (K.stretch > 0)
    visitStretchTerms(x, *Mesh, Rest.length, L, K.stretch, StretchScale, out);
  if (K.shear > 0)
    visitShearTerms(x, *Mesh, Rest.angle, K.shear, out);
  if (K.bend > 0)
    visitBendTerms(x, *Mesh, Rest.cosine, K.bend, HingeWeight, BendScale, out);
}

} // namespace dp

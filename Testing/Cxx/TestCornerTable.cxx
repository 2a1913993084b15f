// SPDX-License-Identifier: BSD-3-Clause
// CornerTable: the remesher's mesh. Its relations (next, prev, the opposite corner) checked
// against the triangle list by brute force on closed, open and non-manifold input, kept so through
// random splits, flips and collapses (a closed sphere stays one: V - E + F = 2), and the quadric
// of planes against its closed form.
#include "FineMeshShapes.h"

#include "dp/geometry/CornerTable.h"
#include "dp/support/Vec3.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace
{

using dp::support::CornerTable;
using dp::support::IndexedMesh;
using dp::support::Vec3;
using dp::support::operator*;

// The corner table with its arrays and operations open to the test.
class Table : public CornerTable
{
public:
  using CornerTable::canFlip;
  using CornerTable::collapse;
  using CornerTable::CornerTable;
  using CornerTable::fan;
  using CornerTable::flip;
  using CornerTable::neighbours;
  using CornerTable::next;
  using CornerTable::onBoundary;
  using CornerTable::prev;
  using CornerTable::split;
  using CornerTable::valence;

  const std::vector<int>& corners() const { return Corner; }
  const std::vector<int>& opposite() const { return Opp; }
  const std::vector<int>& cornerOf() const { return Of; }
  const std::vector<Vec3>& positions() const { return X; }

  std::vector<int> liveCorners() const
  {
    std::vector<int> live;
    for (int c = 0; c < static_cast<int>(Corner.size()); ++c)
      if (Corner[c] >= 0)
        live.push_back(c);
    return live;
  }
  std::size_t liveTriangles() const { return liveCorners().size() / 3; }
};

IndexedMesh indexedMesh(const dp::test::Mesh& m)
{
  IndexedMesh out;
  for (std::size_t i = 0; i < m.vertices(); ++i)
    out.positions.push_back({m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]});
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
    out.triangles.push_back({static_cast<int>(m.triangles[t]), static_cast<int>(m.triangles[t + 1]),
                             static_cast<int>(m.triangles[t + 2])});
  return out;
}

// Each live vertex's neighbours and whether it has an edge of one triangle, from the live
// triangles alone.
struct BruteForce
{
  std::map<int, std::set<int>> neighbours;
  std::set<int> boundary;
  std::size_t edges = 0;
};

BruteForce bruteForce(const Table& m)
{
  BruteForce b;
  std::map<std::pair<int, int>, int> uses; // undirected edge -> triangles
  const std::vector<int>& corner = m.corners();
  for (int c : m.liveCorners())
  {
    const int v = corner[c], w = corner[Table::next(c)];
    b.neighbours[v].insert(w);
    b.neighbours[w].insert(v);
    ++uses[{std::min(v, w), std::max(v, w)}];
  }
  for (const auto& [edge, count] : uses)
    if (count == 1)
    {
      b.boundary.insert(edge.first);
      b.boundary.insert(edge.second);
    }
  b.edges = uses.size();
  return b;
}

// Every relation of the table against the triangle list.
void expectConsistent(const Table& m)
{
  const std::vector<int>& corner = m.corners();
  const std::vector<int>& opp = m.opposite();
  for (int c = 0; c < static_cast<int>(corner.size()); ++c)
  {
    ASSERT_EQ(Table::next(Table::next(Table::next(c))), c);
    ASSERT_EQ(Table::prev(Table::next(c)), c);
    ASSERT_EQ(Table::next(c) / 3, c / 3);
    if (corner[c] < 0)
    {
      ASSERT_EQ(opp[c], -1) << "deleted corner " << c << " keeps an opposite";
      continue;
    }
    const int o = opp[c];
    if (o < 0)
      continue;
    ASSERT_EQ(opp[o], c) << "corner " << c;
    ASSERT_GE(corner[o], 0) << "corner " << c << " faces a deleted corner";
    ASSERT_NE(o / 3, c / 3);
    // The edge facing c is the edge facing o, run the other way.
    ASSERT_EQ(corner[Table::next(c)], corner[Table::prev(o)]) << "corner " << c;
    ASSERT_EQ(corner[Table::prev(c)], corner[Table::next(o)]) << "corner " << c;
  }
  const BruteForce b = bruteForce(m);
  ASSERT_EQ(m.vertices(), b.neighbours.size());
  for (const auto& [v, around] : b.neighbours)
  {
    ASSERT_GE(m.cornerOf()[v], 0) << "vertex " << v << " in use but deleted";
    ASSERT_EQ(corner[m.cornerOf()[v]], v);
    std::vector<int> found;
    const bool boundary = m.neighbours(v, found);
    ASSERT_EQ(found, std::vector<int>(around.begin(), around.end())) << "vertex " << v;
    ASSERT_EQ(boundary, b.boundary.count(v) > 0) << "vertex " << v;
    ASSERT_EQ(m.onBoundary(v), boundary);
    ASSERT_EQ(m.valence(v), static_cast<int>(around.size())) << "vertex " << v;
  }
  // A corner has no opposite exactly where the edge facing it has one triangle.
  std::set<std::pair<int, int>> directed;
  for (int c : m.liveCorners())
    directed.insert({corner[Table::next(c)], corner[Table::prev(c)]});
  for (int c : m.liveCorners())
    ASSERT_EQ(opp[c] < 0, directed.count({corner[Table::prev(c)], corner[Table::next(c)]}) == 0)
        << "corner " << c;
}

TEST(CornerTable, OppositesOnAClosedMeshPairUpAcrossEachEdge)
{
  // The icosahedron subdivided twice: closed, 162 vertices, its 12 first vertices of valence 5
  // and every other of valence 6.
  Table m(indexedMesh(dp::test::icosphere(2)));
  expectConsistent(m);
  EXPECT_TRUE(m.closed());
  EXPECT_EQ(m.vertices(), 162u);
  for (int c = 0; c < static_cast<int>(m.corners().size()); ++c)
    EXPECT_GE(m.opposite()[c], 0);
  for (int v = 0; v < 162; ++v)
    EXPECT_EQ(m.valence(v), v < 12 ? 5 : 6) << "vertex " << v;
  // The fan around a vertex: its corners in order, each the next one's neighbour across an edge.
  std::vector<int> ring;
  EXPECT_FALSE(m.fan(m.cornerOf()[20], ring));
  EXPECT_EQ(ring.size(), 6u);
  for (int c : ring)
    EXPECT_EQ(m.corners()[c], 20);
  dp::support::RemeshedSurface out;
  m.extract(out);
  EXPECT_EQ(out.positions.size(), 3 * 162u);
  EXPECT_EQ(out.triangles.size(), 3 * 320u);
}

TEST(CornerTable, AnOpenGridHasItsBoundaryWhereEdgesHaveOneTriangle)
{
  // 4 x 4 squares: 16 boundary edges, each facing a corner without an opposite.
  Table m(indexedMesh(dp::test::grid(4)));
  expectConsistent(m);
  EXPECT_FALSE(m.closed());
  EXPECT_EQ(m.vertices(), 25u);
  EXPECT_EQ(std::count(m.opposite().begin(), m.opposite().end(), -1), 16);
  EXPECT_EQ(bruteForce(m).boundary.size(), 16u);
  std::vector<int> ring;
  EXPECT_TRUE(m.fan(m.cornerOf()[0], ring));   // a corner of the grid: on the boundary
  EXPECT_FALSE(m.fan(m.cornerOf()[12], ring)); // its centre: inside
}

TEST(CornerTable, NonManifoldEdgesBecomeBoundariesAndEachFanGetsItsVertex)
{
  // Three triangles on one edge: the edge is a boundary of each, and its two ends, each in three
  // fans that no edge joins, become three vertices each: 5 + 2 + 2.
  IndexedMesh three;
  three.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  three.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  Table m(three);
  expectConsistent(m);
  EXPECT_EQ(m.vertices(), 9u);
  EXPECT_EQ(std::count(m.opposite().begin(), m.opposite().end(), -1), 9);

  // Two fans meeting at one vertex (a bow tie): that vertex becomes two, at the same place.
  IndexedMesh bowTie;
  bowTie.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  bowTie.triangles = {{0, 1, 2}, {0, 3, 4}};
  Table tie(bowTie);
  expectConsistent(tie);
  EXPECT_EQ(tie.vertices(), 6u);
  EXPECT_EQ(tie.positions()[5], (Vec3{0, 0, 0}));

  // An edge used twice the same way round (a flipped neighbour): a boundary of both.
  IndexedMesh flipped;
  flipped.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  flipped.triangles = {{0, 1, 2}, {0, 1, 3}};
  Table twice(flipped);
  expectConsistent(twice);
  EXPECT_EQ(std::count(twice.opposite().begin(), twice.opposite().end(), -1), 6);
}

TEST(CornerTable, SplitsFlipsAndCollapsesKeepEveryRelation)
{
  // Random operations on a closed sphere: each keeps the table consistent and the counts its
  // own (a split adds a vertex and two triangles, a collapse takes them away, a flip keeps them
  // and joins the other diagonal), and the sphere stays closed of genus 0.
  Table m(indexedMesh(dp::test::icosphere(2)));
  std::mt19937 rng(7);
  int splits = 0, flips = 0, collapses = 0;
  for (int step = 0; step < 300; ++step)
  {
    const std::vector<int> live = m.liveCorners();
    const int c = live[std::uniform_int_distribution<std::size_t>(0, live.size() - 1)(rng)];
    const std::size_t vertices = m.vertices(), triangles = m.liveTriangles();
    const int a = m.corners()[Table::next(c)], b = m.corners()[Table::prev(c)];
    const int x = m.corners()[c], d = m.corners()[m.opposite()[c]];
    const Vec3 pa = m.positions()[a], pb = m.positions()[b];
    switch (step % 3)
    {
    case 0:
    {
      m.split(c);
      ++splits;
      EXPECT_EQ(m.vertices(), vertices + 1);
      EXPECT_EQ(m.liveTriangles(), triangles + 2);
      const Vec3 mid = m.positions().back();
      for (int k = 0; k < 3; ++k)
        EXPECT_EQ(mid[k], 0.5 * (pa[k] + pb[k]));
      break;
    }
    case 1:
      if (!m.canFlip(c))
        continue;
      m.flip(c);
      ++flips;
      EXPECT_EQ(m.vertices(), vertices);
      EXPECT_EQ(m.liveTriangles(), triangles);
      {
        std::vector<int> around;
        m.neighbours(x, around);
        EXPECT_TRUE(std::binary_search(around.begin(), around.end(), d)) << "no new diagonal";
        m.neighbours(a, around);
        EXPECT_FALSE(std::binary_search(around.begin(), around.end(), b)) << "old diagonal kept";
      }
      break;
    default:
      if (!m.collapse(c, 10.0))
      {
        EXPECT_EQ(m.vertices(), vertices); // a refused collapse changes nothing
        EXPECT_EQ(m.liveTriangles(), triangles);
        continue;
      }
      ++collapses;
      EXPECT_EQ(m.vertices(), vertices - 1);
      EXPECT_EQ(m.liveTriangles(), triangles - 2);
      {
        // The end that stays is at one of the candidates: an end or the midpoint.
        const int keep = m.cornerOf()[a] >= 0 ? a : b;
        const Vec3 p = m.positions()[keep];
        const Vec3 mid{0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1]), 0.5 * (pa[2] + pb[2])};
        EXPECT_TRUE(p == pa || p == pb || p == mid);
      }
    }
    expectConsistent(m);
    if (::testing::Test::HasFatalFailure())
      return;
  }
  EXPECT_GT(splits, 50);
  EXPECT_GT(flips, 10);
  EXPECT_GT(collapses, 10);
  EXPECT_TRUE(m.closed());
  const std::size_t v = m.vertices(), e = bruteForce(m).edges, f = m.liveTriangles();
  EXPECT_EQ(static_cast<long>(v) - static_cast<long>(e) + static_cast<long>(f), 2);
  dp::support::RemeshedSurface out;
  m.extract(out);
  EXPECT_EQ(out.positions.size(), 3 * v);
  EXPECT_EQ(out.triangles.size(), 3 * f);
  for (const std::int64_t i : out.triangles)
    EXPECT_LT(static_cast<std::size_t>(i), v);
}

TEST(CornerTable, ASplitOnTheBoundaryAddsOneTriangleAndCollapsesRespectTheirLimits)
{
  Table grid(indexedMesh(dp::test::grid(3)));
  const auto it = std::find(grid.opposite().begin(), grid.opposite().end(), -1);
  ASSERT_NE(it, grid.opposite().end());
  const std::size_t triangles = grid.liveTriangles();
  grid.split(static_cast<int>(it - grid.opposite().begin()));
  expectConsistent(grid);
  EXPECT_EQ(grid.liveTriangles(), triangles + 1);
  EXPECT_EQ(grid.vertices(), 17u);

  // No collapse that would make an edge longer than allowed; none on a tetrahedron (four
  // vertices are the least a closed surface keeps).
  Table sphere(indexedMesh(dp::test::icosphere(1)));
  for (int c : sphere.liveCorners())
    EXPECT_FALSE(sphere.collapse(c, 0.01));
  EXPECT_EQ(sphere.vertices(), 42u);
  IndexedMesh tetrahedron;
  tetrahedron.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tetrahedron.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  Table tet(tetrahedron);
  expectConsistent(tet);
  EXPECT_TRUE(tet.closed());
  for (int c : tet.liveCorners())
    EXPECT_FALSE(tet.collapse(c, 10.0));
}

TEST(CornerTable, TheQuadricIsTheWeightedSumOfSquaredPlaneDistances)
{
  // Random planes n.x + d = 0 with weights: the quadric at random points against the sum of
  // w (n.x + d)^2, and the sum of two quadrics against the sum of their values.
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  dp::support::Quadric q, r;
  std::vector<std::array<double, 5>> planes; // n, d, w
  for (int i = 0; i < 12; ++i)
  {
    Vec3 n{u(rng), u(rng), u(rng)};
    n = (1 / dp::support::norm(n)) * n;
    const double d = u(rng), w = 1 + u(rng);
    planes.push_back({n[0], n[1], n[2], d, w});
    (i < 6 ? q : r).addPlane(n, d, w);
  }
  dp::support::Quadric sum = q;
  sum += r;
  for (int i = 0; i < 50; ++i)
  {
    const Vec3 x{2 * u(rng), 2 * u(rng), 2 * u(rng)};
    double expectedQ = 0, expectedR = 0;
    for (std::size_t p = 0; p < planes.size(); ++p)
    {
      const auto& [n0, n1, n2, d, w] = planes[p];
      (p < 6 ? expectedQ : expectedR) += w * std::pow(n0 * x[0] + n1 * x[1] + n2 * x[2] + d, 2);
    }
    EXPECT_NEAR(q(x), expectedQ, 1e-12 * (1 + expectedQ));
    EXPECT_NEAR(r(x), expectedR, 1e-12 * (1 + expectedR));
    EXPECT_NEAR(sum(x), expectedQ + expectedR, 1e-12 * (1 + expectedQ + expectedR));
  }
  EXPECT_EQ(dp::support::Quadric{}(Vec3{1, 2, 3}), 0.0);
}

} // namespace

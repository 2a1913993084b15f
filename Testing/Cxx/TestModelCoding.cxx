// SPDX-License-Identifier: BSD-3-Clause
// The geometry's coding over the mesh (dp/compress/ModelCoding.h, MeshPrediction.h): the
// traversal meets every vertex once, each after all it is predicted from; every kind of input
// (random, constant, alternating, extreme, smooth) comes back exactly in both layouts; a smooth
// field costs far less than the same values scattered; and a cut or corrupt stream is refused by
// name or decodes to bounded values, never past the end.
#include "dp/compress/MeshPrediction.h"
#include "dp/compress/ModelCoding.h"
#include "dp/io/AnimatedMesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <set>

namespace
{

using dp::compress::ValueLimit;
using dp::compress::VertexTraversal;

dp::BendingTube tubeMesh(std::size_t rings = 20, std::size_t segments = 16)
{
  dp::BendingTube::Options o;
  o.rings = rings;
  o.segments = segments;
  return dp::BendingTube(o);
}

// A quantised model of `layout` with `k` components over `vertices` and `frames`, every integer
// from `value(part, index)` (part 0 mean, 1 basis, 2 weights).
template <typename Value>
dp::QuantisedPca modelOf(dp::PcaLayout layout, std::size_t vertices, std::size_t frames,
                         std::size_t k, Value value)
{
  dp::QuantisedPca q;
  q.model.layout = layout;
  q.model.vertices = vertices;
  q.model.frames = frames;
  const bool shapes = layout == dp::PcaLayout::Shapes;
  const std::size_t rows = shapes ? 3 * vertices : 3 * frames;
  q.model.basis.resize(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(k));
  for (std::size_t i = 0; i < rows; ++i)
    q.meanIntegers.push_back(value(0, i));
  for (std::size_t i = 0; i < k * rows; ++i)
    q.basisIntegers.push_back(value(1, i));
  for (std::size_t i = 0; i < k * (shapes ? frames : vertices); ++i)
    q.weightIntegers.push_back(value(2, i));
  return q;
}

dp::QuantisedPca roundTrip(const dp::QuantisedPca& q, const VertexTraversal& t,
                           std::size_t* bytes = nullptr)
{
  const std::vector<std::uint8_t> coded = dp::compress::encodeModel(q, t);
  if (bytes)
    *bytes = coded.size();
  dp::QuantisedPca back;
  dp::compress::decodeModel(coded.data(), coded.size(), "m", t, q.model.layout, q.model.frames,
                            q.model.components(), back);
  return back;
}

void expectSameIntegers(const dp::QuantisedPca& a, const dp::QuantisedPca& b, const char* what)
{
  EXPECT_EQ(a.meanIntegers, b.meanIntegers) << what;
  EXPECT_EQ(a.basisIntegers, b.basisIntegers) << what;
  EXPECT_EQ(a.weightIntegers, b.weightIntegers) << what;
}

} // namespace

TEST(ModelCoding, TheTraversalMeetsEveryVertexOnceAfterWhatPredictsIt)
{
  const dp::BendingTube tube = tubeMesh();
  const std::size_t n = tube.numberOfVertices();
  const VertexTraversal t(tube.triangles(), n);
  ASSERT_EQ(t.order.size(), n);
  EXPECT_EQ(std::set<std::size_t>(t.order.begin(), t.order.end()).size(), n);
  std::vector<std::size_t> rank(n);
  for (std::size_t i = 0; i < n; ++i)
    rank[t.order[i]] = i;
  std::size_t surrounded = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    for (std::size_t k = t.start[i]; k < t.start[i + 1]; ++k)
      ASSERT_LT(rank[t.earlier[k]], i) << "vertex " << t.order[i];
    if (i >= t.base)
      ++surrounded;
  }
  // Most vertices are predicted from a whole ring, the base is small, and the finest level's
  // vertices from exactly their mesh neighbours.
  EXPECT_GT(surrounded, n / 2);
  const std::size_t last = t.order.back();
  std::set<std::size_t> ring;
  for (std::size_t i = 0; i < tube.triangles().size(); i += 3)
    for (int e = 0; e < 3; ++e)
      if (static_cast<std::size_t>(tube.triangles()[i + e]) == last)
        for (int o = 1; o < 3; ++o)
          ring.insert(static_cast<std::size_t>(tube.triangles()[i + (e + o) % 3]));
  EXPECT_EQ(
      std::set<std::size_t>(t.earlier.begin() + static_cast<long>(t.start[n - 1]), t.earlier.end()),
      ring);
  // Vertices of no triangle, and no triangles at all, are met too.
  const VertexTraversal loose({0, 1, 2}, 6), none({}, 4);
  EXPECT_EQ(loose.order.size(), 6u);
  EXPECT_EQ(none.order.size(), 4u);
}

TEST(ModelCoding, EveryKindOfInputComesBackExactlyInBothLayouts)
{
  const dp::BendingTube tube = tubeMesh();
  const std::size_t n = tube.numberOfVertices(), frames = 7, k = 5;
  const VertexTraversal t(tube.triangles(), n);
  std::mt19937_64 random(11);
  std::uniform_int_distribution<std::int64_t> any(-ValueLimit, ValueLimit);
  std::geometric_distribution<std::int64_t> small(0.3);
  const std::vector<std::pair<const char*, std::function<std::int64_t(int, std::size_t)>>> kinds = {
      {"zero", [](int, std::size_t) { return std::int64_t{0}; }},
      {"constant", [](int, std::size_t) { return std::int64_t{-123456789}; }},
      {"alternating", [](int, std::size_t i) { return i % 2 ? ValueLimit : -ValueLimit; }},
      {"extreme random", [&](int, std::size_t) { return any(random); }},
      {"small random", [&](int, std::size_t) { return small(random) * (random() % 2 ? 1 : -1); }},
      {"smooth", [](int part, std::size_t i)
       { return static_cast<std::int64_t>(1e4 * std::sin(0.01 * double(i) + part)); }}};
  for (dp::PcaLayout layout : {dp::PcaLayout::Shapes, dp::PcaLayout::Trajectories})
    for (const auto& [name, value] : kinds)
    {
      const dp::QuantisedPca q = modelOf(layout, n, frames, k, value);
      expectSameIntegers(q, roundTrip(q, t), name);
    }
  // No component at all, and one frame.
  const dp::QuantisedPca bare = modelOf(dp::PcaLayout::Trajectories, n, 1, 0, kinds[5].second);
  expectSameIntegers(bare, roundTrip(bare, t), "no component");
}

TEST(ModelCoding, ValuesBeyondTheLimitAreRefused)
{
  const dp::BendingTube tube = tubeMesh();
  const VertexTraversal t(tube.triangles(), tube.numberOfVertices());
  dp::QuantisedPca q = modelOf(dp::PcaLayout::Shapes, tube.numberOfVertices(), 3, 2,
                               [](int, std::size_t) { return std::int64_t{1}; });
  q.weightIntegers[1] = ValueLimit + 1;
  EXPECT_THROW(dp::compress::encodeModel(q, t), std::invalid_argument);
}

// The prediction over the mesh earns its keep: the tube's positions (a smooth field over the
// mesh) cost fewer bytes than the same values scattered over the vertices (measured: 5304 bytes
// against 10 512), and no more than a few percent over what they cost today.
TEST(ModelCoding, ASmoothFieldCostsLessThanTheSameValuesScattered)
{
  const dp::BendingTube tube = tubeMesh(80, 40);
  const std::size_t n = tube.numberOfVertices(), frames = 4, k = 2;
  const VertexTraversal t(tube.triangles(), n);
  const std::vector<double> rest = tube.positions(0);
  auto smooth = [&](int part, std::size_t i) -> std::int64_t
  {
    if (part == 2)
      return static_cast<std::int64_t>(i % 17);
    const std::size_t v = (i % (3 * n)) / 3, j = i / (3 * n);
    return std::llround(300 * rest[3 * v + i % 3] * (1 + 0.3 * double(j)));
  };
  const dp::QuantisedPca q = modelOf(dp::PcaLayout::Shapes, n, frames, k, smooth);
  std::vector<std::size_t> shuffled(n);
  for (std::size_t v = 0; v < n; ++v)
    shuffled[v] = v;
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(5));
  dp::QuantisedPca scattered = q;
  for (std::size_t v = 0; v < n; ++v)
    for (std::size_t a = 0; a < 3; ++a)
    {
      scattered.meanIntegers[3 * v + a] = q.meanIntegers[3 * shuffled[v] + a];
      for (std::size_t j = 0; j < k; ++j)
        scattered.basisIntegers[j * 3 * n + 3 * v + a] =
            q.basisIntegers[j * 3 * n + 3 * shuffled[v] + a];
    }
  std::size_t smoothBytes = 0, scatteredBytes = 0;
  expectSameIntegers(q, roundTrip(q, t, &smoothBytes), "smooth");
  expectSameIntegers(scattered, roundTrip(scattered, t, &scatteredBytes), "scattered");
  EXPECT_LT(smoothBytes, 5460u);
  EXPECT_LT(static_cast<double>(smoothBytes), 0.52 * static_cast<double>(scatteredBytes));
}

TEST(ModelCoding, ACutOrCorruptStreamIsRefusedOrBoundedNeverReadPastItsEnd)
{
  const dp::BendingTube tube = tubeMesh();
  const std::size_t n = tube.numberOfVertices();
  const VertexTraversal t(tube.triangles(), n);
  std::mt19937_64 random(3);
  const dp::QuantisedPca q =
      modelOf(dp::PcaLayout::Trajectories, n, 9, 4,
              [&](int, std::size_t) { return std::int64_t(random() % 200) - 100; });
  const std::vector<std::uint8_t> coded = dp::compress::encodeModel(q, t);
  for (std::size_t cut = 0; cut + 8 < coded.size();
       cut += std::max<std::size_t>(1, coded.size() / 40))
  {
    dp::QuantisedPca back;
    // A copy of exactly `cut` bytes: the sanitizers see any read beyond it.
    const std::vector<std::uint8_t> part(coded.begin(), coded.begin() + static_cast<long>(cut));
    try
    {
      dp::compress::decodeModel(part.data(), part.size(), "cut", t, q.model.layout, 9, 4, back);
      ADD_FAILURE() << "a stream cut to " << cut << " of " << coded.size() << " bytes was read";
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_EQ(std::string(e.what()).rfind("cut: ", 0), 0u) << e.what();
    }
  }
  for (std::size_t i = 0; i < coded.size(); i += 7)
  {
    std::vector<std::uint8_t> bad = coded;
    bad[i] ^= 0xa5;
    dp::QuantisedPca back;
    try
    {
      dp::compress::decodeModel(bad.data(), bad.size(), "bad", t, q.model.layout, 9, 4, back);
      for (const auto* part : {&back.meanIntegers, &back.basisIntegers, &back.weightIntegers})
        for (std::int64_t v : *part)
          ASSERT_LE(std::abs(v), ValueLimit);
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_EQ(std::string(e.what()).rfind("bad: ", 0), 0u) << e.what();
    }
  }
}

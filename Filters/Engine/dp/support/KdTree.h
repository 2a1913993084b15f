// SPDX-License-Identifier: BSD-3-Clause
// A 3-D kd-tree (nanoflann) over x y z triples held elsewhere. Queries are const and
// thread-safe.
#pragma once

#include <nanoflann.hpp>

#include <cmath>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace dp::support
{

class KdTree
{
public:
  /** `points` (3 per point) must outlive the tree and stay unchanged. */
  KdTree(const double* points, std::size_t count)
      : Adaptor{points, count},
        Index(std::make_unique<Tree>(3, Adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)))
  {
  }

  // The nanoflann index keeps a reference to Adaptor: the tree must not move.
  KdTree(const KdTree&) = delete;
  KdTree& operator=(const KdTree&) = delete;

  /** Nearest point to q; its squared distance in *d2. count must be > 0. */
  std::uint32_t nearest(const double q[3], double* d2 = nullptr) const
  {
    std::uint32_t index = 0;
    double distance2 = 0;
    nanoflann::KNNResultSet<double, std::uint32_t> result(1);
    result.init(&index, &distance2);
    Index->findNeighbors(result, q, nanoflann::SearchParams());
    if (d2)
      *d2 = distance2;
    return index;
  }

  /** The k nearest points to q (q itself included when it is a data point). */
  std::size_t nearest(const double q[3], std::size_t k, std::uint32_t* indices, double* d2) const
  {
    return Index->knnSearch(q, k, indices, d2);
  }

  /** Every point within squared distance `radius2` of q (inclusive): (index, squared distance)
   *  pairs, in no particular order. */
  void within(const double q[3], double radius2,
              std::vector<std::pair<std::uint32_t, double>>& found) const
  {
    found.clear();
    // nanoflann keeps what is strictly nearer than the radius.
    Index->radiusSearch(q, std::nextafter(radius2, HUGE_VAL), found,
                        nanoflann::SearchParams(32, 0, false));
  }

  std::size_t memoryBytes() const { return Index->usedMemory(*Index); }

private:
  struct Cloud
  {
    const double* Points;
    std::size_t Count;
    std::size_t kdtree_get_point_count() const { return Count; }
    double kdtree_get_pt(std::size_t i, std::size_t d) const { return Points[3 * i + d]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const
    {
      return false;
    }
  };
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>,
                                                   Cloud, 3, std::uint32_t>;
  Cloud Adaptor;
  std::unique_ptr<Tree> Index;
};

} // namespace dp::support

// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file CoverageTerm.h
 * @brief The points -> mesh data term (beyond the paper): every point of a well-spread
 *        subsample of the frame's data pulls the closest point of the mesh surface, so a part of
 *        the mesh that has let go of its data (a limb left behind by fast motion) is pulled back;
 *        the paper's mesh -> points term alone lets the mesh lose data at no cost.
 *
 *   E_cov = k_cov / (N L voxel) * sum_p w_p / 2 [ (n_p . (s_p(x) - p))^2 + mu |s_p(x) - p|^2 ],
 *   s_p(x) = sum_k b_pk x_{t_p,k}
 *
 * over the N subsample points p with unit normal n_p; s_p is the closest point of the mesh to p,
 * on triangle t_p with barycentric weights b_p (held during a step, decided again at every
 * linearisation, as in ICP). The point-to-plane part lets the mesh slide along the data; the
 * small point-to-point part (mu) keeps it from sliding off. Weights w_p: 0 when the mesh's
 * normal at s_p and n_p differ by more than normalTestDegrees (the point belongs to another
 * part, e.g. the inner side of a limb facing the body) or when s_p is farther than
 * maxDistance; else Geman-McClure 1 / (1 + (d/s)^2)^2 of the distance d = |s_p - p| (outliers
 * and points of a part the mesh is far from pull little). Each point weighs 1/N: with k_cov =
 * k_dis both directions have the same total weight.
 *
 * For fixed correspondences the term is quadratic in x; its Gauss-Newton model is exact and
 * couples the three vertices of each triangle (the mesh's edges), or, on request, is replaced
 * by a diagonal upper bound that couples nothing (the coarse level's cheaper systems).
 *
 * Closest points: the first linearisation, and the next after searchWholeSurface(), searches the
 * whole surface (SurfaceLocator::closest, a tree query per point). With followMatches (off by
 * default) the others walk from each point's last triangle to a locally closest one
 * (SurfaceLocator::follow, about four triangle tests a point), as the mesh moves little between
 * the steps of a solve; a point that had no match, or whose walk ends farther than a voxel
 * (where another part may be nearer) or beyond maxDistance, is searched everywhere.
 *
 * Limits: the normal test needs oriented normals, consistent with the mesh's (outward/outward);
 * a followed match within a voxel of its point may still miss a nearer part of the surface
 * (parts closer than a voxel; the tracker searches everything at each coarse stage's start and at
 * the fine level's).
 */
#pragma once

#include "dp/geometry/FrameSamples.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/geometry/TriangleMesh.h"
#include "dp/track/EnergyTerm.h"
#include "dp/track/TrackerOptions.h"

#include <cstdint>
#include <vector>

namespace dp
{

class CoverageTerm : public EnergyTerm
{
public:
  /** The samples' arrays and the mesh must outlive the term. */
  CoverageTerm(const SampleView& samples, const TriangleMesh& mesh, double lengthScale,
               const CoverageOptions& options);

  const char* name() const override { return "coverage"; }
  double evaluate(const double* x, double* gradient) const override;
  double addModel(const double* x, support::BlockSparseMatrix& hessian,
                  double* gradient) const override;
  /** Closest points, normal test and robust weights at x (kept as they are while no vertex has
   *  moved a fifth of a voxel since they were decided). */
  void linearise(const double* x) override;
  void couplings(std::vector<std::array<std::int64_t, 2>>& pairs) const override;
  /** The next linearise() searches the whole surface for every point (see the file comment). */
  void searchWholeSurface() { WholeSurface = true; }

  /** With a diagonal model, addModel() gives each vertex only its own block, an upper bound of
   *  the term (see addModel), so vertices are not coupled: cheaper systems, slower steps. */
  void setDiagonalModel(bool diagonal) { DiagonalModel = diagonal; }
  void setRobustScale(double scale) { Options.robustScale = scale; }
  void setMaxDistance(double distance) { Options.maxDistance = distance; }
  const CoverageOptions& options() const { return Options; }

  /** One subsample point's correspondence. */
  struct Match
  {
    std::uint32_t point = 0;    // the sample
    std::int64_t triangle = -1; // -1: no pull
    double barycentric[3] = {0, 0, 0};
    double weight = 0;
  };
  const std::vector<Match>& matches() const { return Matches; }

private:
  // s_p(x) - p for a match.
  // One match at x: r = the closest surface point - the data point, the data normal n, n.r and
  // the match's weight c; returns its energy c / 2 ((n.r)^2 + mu |r|^2).
  struct Pull
  {
    double r[3], n[3], along, c;
  };
  double pull(const double* x, const Match& m, Pull& p) const;
  // Whether the matches last decided still hold at x: no vertex moved a fifth of a voxel since,
  // the same robust scale and reach, and no search of the whole surface asked for.
  bool matchesHold(const double* x) const;
  // The locator over the mesh at x: built the first time, refitted after.
  void placeLocator(const double* x);

  SampleView Samples;
  const TriangleMesh& Mesh;
  CoverageOptions Options;
  double Scale = 0; // k_cov / (N L voxel)
  SurfaceLocator Locator;
  bool Built = false;
  std::vector<Match> Matches;
  std::vector<std::int64_t> Hints; // per match, the closest triangle last found (search hint)
  bool DiagonalModel = false;
  bool WholeSurface = true; // the next linearise() searches the whole surface
  // Where the correspondences were last decided, and with which scale and reach.
  std::vector<double> LinearisedAt;
  double LinearisedScale = 0, LinearisedReach = 0;
};

} // namespace dp

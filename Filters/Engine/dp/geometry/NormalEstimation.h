// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file NormalEstimation.h
 * @brief Normals for point clouds that come without them (scans, most 3D video): local PCA,
 *        then one orientation spread over the cloud.
 *
 * Limits: orientation is a guess per connected part (see estimateNormals); parts thinner than
 * the neighbourhood (a hand on the body) and regions beyond a sharp rim (a foot's) can still be
 * oriented inward, which the tracker corrects against its mesh: part by part, then branch by
 * branch of the orientation's tree (mendOrientation).
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dp
{

/** The spanning forest estimateNormals carried the orientation along. */
struct OrientationTree
{
  std::vector<std::uint32_t> parent; // per point: where its orientation came from (a seed: itself)
  std::vector<std::uint32_t> order;  // the points in the order they were oriented: parents first
};

/**
 * Unit normals of a point cloud by PCA over each point's `neighbours` nearest points, oriented
 * consistently: orientation spreads along a minimum spanning tree of the neighbour graph
 * (Hoppe et al. 1992) from, in each connected part, the point of largest x, whose normal is
 * made to point to +x (outward on a closed surface). Returns nx ny nz per point; `parts`, when
 * given, receives each point's part (0, 1, ... in the order the parts were seeded), since the
 * +x rule can orient a small part (a patch cut off by a hole) inward while the rest is right;
 * `tree`, when given, the tree the orientation spread along (for mendOrientation).
 */
std::vector<float> estimateNormals(const double* points, std::size_t count,
                                   std::size_t neighbours = 16,
                                   std::vector<std::uint32_t>* parts = nullptr,
                                   OrientationTree* tree = nullptr);

/** The same normals before their orientation (each may point either way): local PCA over each
 *  point's `neighbours` nearest points, for a caller that reads only the normal's line. */
std::vector<float> unorientedNormals(const double* points, std::size_t count,
                                     std::size_t neighbours = 16);

/**
 * Turns around the branches of estimateNormals' tree that a reference surface disagrees with as
 * a whole. The tree can carry a wrong orientation across a sharp edge where PCA smears the
 * normals of both sides into one direction (the rim of a foot): everything beyond that edge is
 * then inward, while the edge's own weight looked sure. `votes` holds, per point, +1 where a
 * reference (the tracked mesh) agrees with its normal, -1 where it disagrees, 0 where it was
 * asked and says nothing (no surface near), NotAsked where it was not asked. An edge of the
 * tree inside a part is cut, and the wrong side's normals (and votes) turned, when the votes on
 * both sides of it are each at least `minimumVotes`, from at least `coverage` of the side's
 * asked points, and `share` one way: agreeing on one side, disagreeing on the other. The edge
 * whose wrong side holds the most disagreement goes first (ties: the first in the tree's
 * order), then the sums are taken again, at most `maximumCuts` times. Returns the number of
 * points turned. Serial and deterministic, O(points) per cut.
 *
 * Limits: a side is a whole branch of the tree or the rest of its part, so only errors made at
 * one edge each are found; the reference must be near and right (a reference displaced by
 * about its own thickness can vote a right side wrong, which `coverage` guards against, not
 * excludes); where between the last vote for and the first against the cut falls is a guess;
 * a side too small to gather `minimumVotes` stays as it is.
 */
struct MendOptions
{
  std::size_t minimumVotes = 20;
  double share = 0.8;
  double coverage = 0.4; // the least share of a side's asked points that must vote
  int maximumCuts = 8;
};
/** A point mendOrientation's reference was not asked about (0: asked, but silent). */
constexpr std::int8_t NotAsked = 2;
std::size_t mendOrientation(const OrientationTree& tree, const std::vector<std::uint32_t>& parts,
                            std::vector<std::int8_t>& votes, float* normals,
                            const MendOptions& options = {});

} // namespace dp

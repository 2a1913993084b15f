// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file ClothEnergy.h
 * @brief The deformation energy E_int of the paper (after Baraff & Witkin's cloth):
 *
 *   E_int = 1/2 sum_edges   k_st        ((l - l0) / L)^2
 *         + 1/2 sum_corners k_sh        (theta - theta0)^2
 *         + 1/2 sum_hinges  k_ben w_h   (cos phi - cos phi0)^2
 *
 * over the template's edges (stretch), triangle corners (shear: in-plane corner angles) and
 * hinges (bend: cos of the angle between the normals of two triangles sharing an edge). Rest
 * values come from the template. L = sqrt(template area) makes every term dimensionless, so
 * the energy and its minimisers do not depend on the data's units. Following the paper's rule,
 * k_st and k_sh are constants, while the bending weight of a hinge w_h = (A_1 + A_2) / (3 A)
 * (its share of the template's area A), so that totals do not change when the same shape is
 * subdivided. vertexMass() gives the matching masses m_i = A_i / A (summing to 1).
 *
 * Shear is off by default (k_sh = 0): a triangulated surface whose edge lengths are held keeps
 * its in-plane shape, and the angle terms measurably pull tracked shapes away from the truth
 * (BenchmarkTracker, Documentation/Tracking.md). A template with slivers (nearly flat triangles)
 * needs them: with edges alone a sliver's apex slides across its base at almost no cost.
 *
 * Limits: the template must have no (nearly) degenerate triangle (area under 1e-12 of the mean:
 * refused with its index); degenerate triangles in the *current* shape give zero shear/bend
 * gradients for their corners/hinges instead of NaN.
 */
#pragma once

#include "dp/geometry/TriangleMesh.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace dp
{

struct ClothParameters
{
  double stretch = 1.0; // k_st
  double shear = 0.0;   // k_sh: 0 = in-plane shape held by the edges alone (see below)
  double bend = 0.5;    // k_ben
};

/** One term of E_int: its energy, its residual r and r's gradient with respect to each of its
 *  vertices (2 for stretch, 3 for shear, 4 for bend), and its stiffness: the term is
 *  1/2 weight r^2, so dE/dx = weight * r * grad(r). */
struct ClothTerm
{
  double energy = 0;
  double weight = 0;
  double residual = 0;
  int count = 0;
  std::int64_t vertex[4] = {0, 0, 0, 0};
  double gradient[4][3] = {};
};

/** The rest values of E_int's terms: per edge, per triangle corner, per hinge. */
struct ClothRestState
{
  std::vector<double> length; // per edge
  std::vector<double> angle;  // per corner (3 per triangle)
  std::vector<double> cosine; // per hinge

  /** (1 - t) * a + t * b, term by term. */
  static ClothRestState blend(const ClothRestState& a, const ClothRestState& b, double t);
};

class ClothEnergy
{
public:
  ClothEnergy(const TriangleMesh& mesh, const double* restPositions, const ClothParameters& k);

  /** E_int at x (3 per vertex). */
  double value(const double* x) const;
  /** E_int at x; adds dE/dx to gradient (which must be sized 3 * vertices). */
  double addGradient(const double* x, double* gradient) const;
  /** Visits every term at x (for Gauss-Newton: the Hessian of a term is about
   *  weight * grad(r) grad(r)^T). Degenerate terms come with zero gradients. */
  void forEachTerm(const double* x, const std::function<void(const ClothTerm&)>& visit) const;

  /** The rest values a shape would have (same mesh). */
  ClothRestState restStateOf(const double* positions) const;
  /** Replaces the rest values; masses, bending weights and L stay the template's, so the
   *  parameter rule and the units still hold. */
  void setRestState(ClothRestState rest);
  const ClothRestState& restState() const { return Rest; }
  /** Scales k_st edge by edge and k_ben hinge by hinge (a stiffer or softer region); empty
   *  vectors are all 1. Throws std::invalid_argument for sizes other than the mesh's or
   *  negative or non-finite scales. */
  void setStiffnessScales(std::vector<double> edgeStretch, std::vector<double> hingeBend);
  /** The per-edge factors on k_st (empty: 1 everywhere). */
  const std::vector<double>& stretchScales() const { return StretchScale; }

  const std::vector<double>& vertexMass() const { return Mass; }
  double lengthScale() const { return L; }
  const TriangleMesh& mesh() const { return *Mesh; }
  const ClothParameters& parameters() const { return K; }

private:
  const TriangleMesh* Mesh;
  ClothParameters K;
  double L = 1.0;
  ClothRestState Rest;
  std::vector<double> HingeWeight;  // per hinge
  std::vector<double> StretchScale; // per edge; empty: 1
  std::vector<double> BendScale;    // per hinge; empty: 1
  std::vector<double> Mass;         // per vertex
};

} // namespace dp

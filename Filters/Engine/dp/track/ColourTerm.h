// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file ColourTerm.h
 * @brief Colour as a cue along the surface (beyond the paper): where the points carry colour, each
 *        vertex is pulled to where the frame's colour is the colour its material point had in the
 *        first frame. Geometry says where the surface is, not where on it a vertex lies; a colour
 *        pattern fixed to the material does (Prada et al. 2017 cut the drift of tracked meshes
 *        with mesh-based optical flow the same way).
 *
 * The frame's colour field (ColourField) is a Gaussian-weighted mean of its points' colours:
 *
 *   C(x) = sum_p w_p c_p / sum_p w_p,   w_p = exp(-|x - p|^2 / (2 s^2)),  |x - p| < 3 s,
 *
 * smooth in x, with the analytic Jacobian dC/dx = sum_p w_p (c_p - C) (p - x)^T / (s^2 sum_p w_p).
 * A wide kernel reads the points' means over grid cells at most its width (each weighing as many
 * points as it holds) instead of every point: nearly the same mean, far fewer terms.
 * The term is
 *
 *   E_col = k_col / (L voxel) * sum_i m_i / 2 * l^2 |C(x_i) - c_i|^2
 *
 * over the vertices i with a reference colour c_i and points within reach, l = ColourLength
 * voxels turning a colour difference (0 to 1 per channel) into a length, so k_col weighs like
 * the data terms' weights. The colour moves vertices along the surface only: between two
 * linearisations (at x0, with the mesh's vertex normals n_i there) the colour is read at
 * x0_i + (I - n_i n_i^T)(x_i - x0_i), so J_i = dC/dx (I - n_i n_i^T) (the kernel's blur also
 * varies across the surface, which the geometry, not the colour, should decide). Its
 * Gauss-Newton model is k m_i l^2 J_i^T J_i on each vertex's own block (it couples no vertices).
 *
 * Limits: a local cue, whose reach is the pattern's scale and the kernel's (s: solve coarse to
 * fine); colours that change with the view or the light (real captures) mislead it; a uniform
 * colour says nothing.
 */
#pragma once

#include "dp/geometry/TriangleMesh.h"
#include "dp/track/EnergyTerm.h"

#include <memory>
#include <vector>

namespace dp
{

namespace support
{
class KdTree;
}

/** A frame's colour field over its points with colour. */
class ColourField
{
public:
  /** Over `count` points (x y z each) with colours (r g b in [0, 1] each), whose typical spacing
   *  is `spacing`, in a frame of voxel `voxel`; the arrays must outlive the field. */
  ColourField(const double* points, const float* colours, std::size_t count, double spacing,
              double voxel);
  ~ColourField();
  ColourField(const ColourField&) = delete;
  ColourField& operator=(const ColourField&) = delete;

  /** C(x) at kernel width `sigma` into rgb and, when `jacobian` is not null, dC/dx (row-major
   *  3 x 3: a row per channel). Returns the weights' sum (0: no point within 3 sigma; rgb and
   *  jacobian then untouched). Thread-safe. */
  double sample(const double x[3], double sigma, double rgb[3], double* jacobian = nullptr) const;

  /** The kernel width that resolves the field: 1 point spacing, at least a voxel (`scale` times
   *  that). */
  double kernel(double scale = 1.0) const;

private:
  struct Level;
  double Spacing, Voxel;
  std::vector<std::unique_ptr<Level>> Levels; // the points, then their means over coarser cells
};

/** Each vertex's colour in a frame: C at the vertex (kernel width `sigma`), or `previous`'s where
 *  no point lies within 3 sigma (a hole keeps the last colour); 3 per vertex in [0, 1]. Without
 *  a previous colour such a vertex gets -1. */
std::vector<float> vertexColours(const ColourField& field, const double* positions,
                                 std::size_t vertices, double sigma,
                                 const std::vector<float>* previous = nullptr);

class ColourTerm : public EnergyTerm
{
public:
  /** `reference` (3 per vertex; a negative red: no reference), `mass` and the field must
   *  outlive the term. */
  ColourTerm(const ColourField& field, const TriangleMesh& mesh,
             const std::vector<float>& reference, const std::vector<double>& mass, double weight,
             double lengthScale, double voxel, double sigma);
  /** Another kernel width, with the references read at it (which must outlive the term). */
  void setKernel(double sigma, const std::vector<float>& reference);

  const char* name() const override { return "colour"; }
  double evaluate(const double* x, double* gradient) const override;
  double addModel(const double* x, support::BlockSparseMatrix& hessian,
                  double* gradient) const override;
  /** The mesh's vertex normals at x, and the model there: until the next linearisation the term
   *  reads each vertex's colour as if it moved along the surface only. */
  void linearise(const double* x) override;

private:
  // Vertex v's share: its energy, and (when asked) the residual and the Jacobian.
  double vertexEnergy(const double* x, std::size_t v, double residual[3], double* jacobian) const;

  const ColourField& Field;
  const TriangleMesh& Mesh;
  const std::vector<float>* Reference;
  const std::vector<double>& Mass;
  double Scale; // k_col l^2 / (L voxel)
  double Sigma;
  std::vector<double> Normals; // per vertex at the last linearisation (empty: none yet)
  // The vertices' energies, residuals and Jacobians at the last linearisation.
  struct VertexModel
  {
    double energy = -1; // -1: no colour there
    double residual[3] = {0, 0, 0};
    double jacobian[9] = {};
  };
  std::vector<VertexModel> Linearised;
  std::vector<double> LinearisedAt;
};

} // namespace dp

// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Decomposition.h
 * @brief The principal components of an animated mesh (the paper's Sec. 4, after Alexa & Mueller
 *        for the shape layout and Sattler et al. for the trajectory layout): the thin SVD of the
 *        centred data, computed through the eigen-decomposition of the Gram matrix of its smaller
 *        side, so that the cost is that of a frames x frames (or vertices x vertices) problem.
 *
 * Internal to the compression (dp::compressSequence); not installed API. Limits: singular values
 * under 1e-8 of the largest are dropped as noise of the Gram route, which squares the condition
 * number: components weaker than that are not resolved.
 */
#pragma once

#include "dp/compress/PcaCompression.h"

#include <Eigen/Core>

namespace dp::compress
{

/** The centred data and its singular values and vectors, in the layout asked for. */
struct Decomposition
{
  PcaLayout layout = PcaLayout::Shapes;
  std::size_t vertices = 0, frames = 0;
  Eigen::VectorXd mean;
  Eigen::MatrixXd centred;    // Shapes: 3Nv x Nt; Trajectories: Nv x 3Nt
  Eigen::VectorXd sigma;      // descending, rank-cut
  Eigen::MatrixXd smallSide;  // eigenvectors of the Gram matrix, columns in sigma's order
  bool gramOfColumns = false; // true: Gram = C^T C (small side = right vectors)
  double centredNorm2 = 0;    // ||C||_F^2

  /** The orthonormal basis (k columns) and the weights carrying sigma (k columns). */
  void factors(std::size_t k, Eigen::MatrixXd& basis, Eigen::MatrixXd& weights) const;
  /** ||C - C_k||_F: the error of keeping k components, before quantisation. */
  double truncationError(std::size_t k) const;
  /** How often the mean is repeated in a reconstruction (frames or vertices). */
  std::size_t meanRepeats() const { return layout == PcaLayout::Shapes ? frames : vertices; }
};

/** Decomposes A (3Nv x Nt, a frame per column) in `layout`. */
Decomposition decompose(const Eigen::Map<const Eigen::MatrixXd>& A, PcaLayout layout);

/** KG error (percent) and largest vertex error of a model against A. */
struct Errors
{
  double kg, max;
};
Errors errorsOf(const Eigen::Map<const Eigen::MatrixXd>& A, const PcaModel& m);
/** What `measure` reads from `e`: KG in percent, or the largest error over `diagonal`. */
double measured(const Errors& e, PcaErrorMeasure measure, double diagonal);

} // namespace dp::compress

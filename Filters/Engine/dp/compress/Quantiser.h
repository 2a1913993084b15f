// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Quantiser.h
 * @brief Uniform quantisation of a PCA model for coding (beyond the paper, which stores floats):
 *        weights at step q, basis vector j at q / sigma_j (its weights carry sigma_j, so each
 *        contributes about the same error to the reconstruction), the mean at q / sqrt(its
 *        repeats). With every stored number rounded, the reconstruction error is about q^2 / 12
 *        per number, which the bit-rate search (compressSequence) turns into the step it tries.
 *
 * Internal to the compression; not installed API. Limits: steps are positive and finite (the
 * caller's search guarantees it); values beyond +-2^62 steps would not fit the integers.
 */
#pragma once

#include "dp/compress/Decomposition.h"

namespace dp::compress
{

/** The model of `basis` and `weights` (k columns each, from d.factors) quantised at `step`. */
QuantisedPca quantise(const Decomposition& d, const Eigen::MatrixXd& basis,
                      const Eigen::MatrixXd& weights, double step);

// ||X - X'||^2 of a quantised model in the KG search, without reconstructing the sequence.
// In both layouts the data, in the model's orientation, is X = m 1^T + B W^T + R (B the
// orthonormal basis, W = C^T B, R the truncation residual: B^T R = 0, R 1 = 0, ||R||^2 from
// the singular values), and the model is X' = m_q 1^T + B_q W_q^T. Then
// X' - X = D - R with D = (m_q - m) 1^T + (B_q - B) W_q^T + B (W_q - W)^T, and
// ||X' - X||^2 = ||D||^2 + ||R||^2 - 2 tr(W_q (B_q - B)^T R). The last term, quantisation noise
// against the residual, is left out (its mean is 0); the search checks its final step on the
// actual reconstruction. ||D||^2 = tr((P^T P)(Q^T Q)) with D = P Q^T, on k x k blocks.
double estimatedError2(const Eigen::MatrixXd& basis, const Eigen::MatrixXd& weights,
                       const Eigen::VectorXd& mean, const PcaModel& q, double residual2);

} // namespace dp::compress

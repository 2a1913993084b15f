// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file PcaCompression.h
 * @brief Compression of a mesh sequence of fixed connectivity by principal component analysis
 *        of its vertex positions (Shinya, Shioya & Shiraishi, section 8; Alexa & Mueller 2000),
 *        then quantisation, prediction over the mesh and along time, and adaptive range coding.
 *
 * The sequence is A, 3Nv x Nt (column t = frame t's x y z per vertex). Two layouts:
 *   Trajectories (the paper): rows are vertices, B = Nv x 3Nt (row i = vertex i's trajectory);
 *     X_i[t] = m[t] + sum_j c_ij Y_j[t] with m the centroid trajectory, Y_j orthonormal
 *     trajectories (basis, 3Nt each) and c_ij per-vertex weights. D1 = 3 Nt nY + Nv nY.
 *   Shapes (Alexa & Mueller, glTF morph targets): A = m 1^T + sum_j U_j w_j^T with m the mean
 *     shape, U_j orthonormal shapes (basis, 3Nv each) and w_j per-frame weights.
 * In both the basis is orthonormal and the weights carry the singular values. The thin SVD is
 * computed through the Gram matrix of the smaller side (the snapshot method): memory is the
 * data (3 Nv Nt doubles: 2.4 GB for 100k vertices x 1000 frames), its centred copy, and a
 * min(3Nv, Nt)^2 (Shapes) or min(Nv, 3Nt)^2 (Trajectories) Gram matrix (8 MB / 72 MB there).
 *
 * Error measures: Karni & Gotsman's KG = 100 ||A - A'||_F / ||A - E(A)||_F (E(A): each frame's
 * centroid), or the largest vertex error relative to the diagonal of the sequence's bounding
 * box.
 *
 * The codec (quantise = true): one quantisation step q in position units; the weights use q,
 * basis vector j uses q / sigma_j and the mean q / sqrt(times it is repeated), so every stored
 * number adds about q^2 / 12 to ||A - A'||^2. The integers are coded by ModelCoding.h: the
 * per-vertex ones (mean and basis of Shapes, weights of Trajectories) in a decimation order of
 * the mesh, each predicted from its ring (the mean, or a regression learnt from the vertex's
 * stronger components); those along time (weights of Shapes; basis of Trajectories; the
 * centroid trajectory) from the previous one or two values; the predictor chosen per column,
 * the residuals range-coded under contexts of their neighbours' size.
 * The component count and q are chosen for the fewest bytes that meet the target: for the KG
 * error q is searched on an estimate computed from k x k blocks (no reconstruction), and the
 * chosen q is checked on the actual reconstruction (stepped down until it holds); the max
 * vertex error is searched on reconstructions.
 *
 * Limits: the whole sequence is in memory; the SVD through a Gram matrix loses components whose
 * singular value is under ~1e-8 of the largest (far below any useful target).
 */
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace dp
{

enum class PcaLayout : std::uint8_t
{
  Trajectories = 0, // the paper: basis = trajectories, weights per vertex
  Shapes = 1,       // Alexa & Mueller: basis = shapes, weights per frame
  Automatic = 2     // an option only: both are coded and the one of fewer bits is kept (a model
                    // and a file always hold one of the two)
};

enum class PcaErrorMeasure
{
  KarniGotsman,   // target in percent
  MaxVertexError, // target as a fraction of the bounding-box diagonal
  // Target in the positions' own units: the RMS distance of the decompressed vertices from the
  // originals over all frames. It is KG's numerator (KG = 100 RMS sqrt(Nv Nt) / ||A - E(A)||),
  // so it is searched as KG is; a target a user can read ("1.5 mm") and one a caller can derive
  // from the data (dp::compressAgainstData).
  RmsDeviation
};

/** The KG targets a compression may ask for, in percent: below 1e-4 % the coding is lossless
 *  in practice, above 50 % little of the motion is left (dp::compressionOptions() gives the
 *  range to every front end). */
constexpr double MinimumKarniGotsmanTarget = 1e-4;
constexpr double MaximumKarniGotsmanTarget = 50;
/** The growth of the distance to the data a compression may allow, in percent
 *  (dp::compressAgainstData, DISTANCE_TO_DATA, the main job's --fit-growth). */
constexpr double MinimumFitGrowth = 0.01;
constexpr double MaximumFitGrowth = 1000;

struct PcaOptions
{
  PcaLayout layout = PcaLayout::Automatic;
  PcaErrorMeasure measure = PcaErrorMeasure::KarniGotsman;
  double target = 0.2;        // KG in %, max vertex error / diagonal, or RMS deviation
  std::size_t components = 0; // > 0: this many, and the target only sets the quantisation
  bool quantise = true;       // false: the paper's float PCA (no quantisation, no coding)
};

/** A decomposed sequence: frame(t) = mean + basis x weights, in either layout. */
struct PcaModel
{
  PcaLayout layout = PcaLayout::Shapes;
  std::size_t vertices = 0, frames = 0;
  Eigen::VectorXd mean;    // Shapes: 3Nv mean shape; Trajectories: 3Nt centroid trajectory
  Eigen::MatrixXd basis;   // Shapes: 3Nv x k; Trajectories: 3Nt x k (x y z per frame)
  Eigen::MatrixXd weights; // Shapes: Nt x k; Trajectories: Nv x k

  std::size_t components() const { return static_cast<std::size_t>(basis.cols()); }
  /** Frame t's positions, 3 Nv values. */
  void frame(std::size_t t, double* positions) const;
  /** All frames, 3Nv x Nt. */
  Eigen::MatrixXd reconstruct() const;
};

/** Quantised model: the integers the codec stores and the steps that scale them. */
struct QuantisedPca
{
  PcaModel model;                 // the dequantised values (what a reader reconstructs)
  double step = 0;                // q, position units
  double meanStep = 0;            // q / sqrt(repeats of the mean)
  std::vector<double> basisSteps; // q / sigma_j
  std::vector<std::int64_t> meanIntegers, basisIntegers, weightIntegers; // column-major
};

struct PcaReport
{
  std::size_t components = 0;
  double paperD0 = 0, paperD1 = 0, paperRatio = 0; // the paper's counts of numbers
  double kgError = 0;                              // percent
  double maxError = 0;                             // position units
  double maxErrorRelative = 0;                     // / diagonal
  double rmsError = 0;                             // position units, over all vertices and frames
  double diagonal = 0;                             // of the sequence's bounding box
  double bitsPerVertexFrame = 0; // what is stored for the geometry, per vertex per frame
  double quantisedPlainBits = 0; // the same integers in fixed-width fields, no coding
  std::size_t payloadBytes = 0;  // geometry, compressed (0 for float PCA)
  std::size_t colourBytes = 0;   // the colour stream, compressed (0: no colour)
  std::size_t detailBytes = 0;   // the detail layer's section (0: no detail layer)
  int colourTolerance = 0;       // levels a stored colour may differ from the given one
};

/**
 * The optional detail layer over the compressed (base) mesh: the base subdivided `levels` times
 * (SubdivisionMap) and each fine vertex moved along the subdivided surface's normal by its
 * displacement (dp::detailedFrame). `displacements` are the decoded values, frame-major (frame t
 * starts at fine vertices * t); `payload` the range coder's bytes the file stores
 * (dp::encodeDetail), made from them at `step`.
 */
struct DetailLayer
{
  int levels = 0; // 0: no detail layer
  double step = 0;
  std::vector<double> displacements;
  std::vector<std::uint8_t> payload;
};

struct CompressedSequence
{
  QuantisedPca pca;                    // for float PCA: model only, steps 0
  std::vector<std::int64_t> triangles; // connectivity, stored once
  std::vector<double> times;           // one per frame
  // Optional colour of every vertex in every frame: r g b bytes, frame-major (frame t starts at
  // 3 * vertices * t); empty: no colour. Stored beside the geometry as setColours left them.
  std::vector<std::uint8_t> colours;
  DetailLayer detail;
  PcaReport report;
};

/**
 * Decomposes and compresses `frames` x 3`vertices` positions (frame-major: frame t starts at
 * 3 * vertices * t); with PcaLayout::Automatic in both layouts, keeping the fewer bits (ties to
 * the shapes). Throws std::invalid_argument for empty or non-finite input or a target
 * out of range. `progress` (may be empty) is called with a fraction in [0, 1], on the caller's
 * thread only; returning false aborts (std::runtime_error "aborted"). The candidate component
 * counts are coded on several threads (TBB; as many at once as fit in 1 GiB of working memory):
 * the result is the same, byte for byte, for any thread count.
 */
CompressedSequence compressSequence(const double* positions, std::size_t vertices,
                                    std::size_t frames, const PcaOptions& options,
                                    const std::vector<std::int64_t>& triangles = {},
                                    const std::vector<double>& times = {},
                                    const std::function<bool(double)>& progress = {});

/** KG error in percent of reconstruction `approx` against `original` (both 3Nv x Nt). */
double karniGotsmanError(const Eigen::Ref<const Eigen::MatrixXd>& original,
                         const Eigen::Ref<const Eigen::MatrixXd>& approx);
/** ||A - E(A)||_F (E(A): each frame's centroid repeated), KG's denominator. */
double centroidSpread(const Eigen::Ref<const Eigen::MatrixXd>& A);
/** Largest vertex distance between the two (both 3Nv x Nt). */
double maxVertexError(const Eigen::Ref<const Eigen::MatrixXd>& original,
                      const Eigen::Ref<const Eigen::MatrixXd>& approx);

/**
 * The compressed file (.dpz): magic, version, a header with its CRC-32, and sections, each with
 * its CRC-32: the connectivity (range-coded, ConnectivityCoding.h, from version 5 on; zstd
 * before), the geometry (mean, basis, weights: range-coded over the mesh, ModelCoding.h, from
 * version 4 on; predicted zigzag varints through zstd in versions 1 to 3),
 * in version 2 the colours (each frame's bytes as differences from the previous frame's, zstd,
 * so colour fixed to the surface costs little), and from version 3 on a byte of flags saying
 * which of the colours and the detail layer (its levels, step and range-coded displacements,
 * DetailCoding.h) follow; version 5 also writes evenly spaced frame times as their first and
 * step. This writer writes version 5; this reader reads all five. The reader
 * checks every length, count and checksum and throws std::runtime_error naming the file and what is
 * wrong; it never returns partial geometry, colour or detail. Writing throws std::invalid_argument
 * when the colours' count is neither 0 nor frames * vertices * 3, or the detail layer's
 * displacements do not match its levels.
 */
void writeCompressedSequence(const std::string& path, const CompressedSequence& sequence);
CompressedSequence readCompressedSequence(const std::string& path);
/** The same, in memory (the file's bytes). `name` is used in error messages. */
std::vector<std::uint8_t> encodeCompressedSequence(const CompressedSequence& sequence);
CompressedSequence decodeCompressedSequence(const std::uint8_t* bytes, std::size_t size,
                                            const std::string& name);

} // namespace dp

// SPDX-License-Identifier: BSD-3-Clause
#include "dp/PcaCompression.h"

#include <Eigen/Eigenvalues>

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace dp
{
namespace
{

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Singular values under this share of the largest are noise of the Gram-matrix route.
constexpr double RankCut = 1e-8;
constexpr char Magic[8] = {'\x89', 'D', 'P', 'Z', '\r', '\n', '\x1a', '\n'};
constexpr std::uint32_t FormatVersion = 1;

// ---------------------------------------------------------------------------------------------
// Thin SVD of the centred data through the Gram matrix of its smaller side.

struct Decomposition
{
  PcaLayout layout;
  std::size_t vertices, frames;
  VectorXd mean;
  MatrixXd centred;    // Shapes: 3Nv x Nt; Trajectories: Nv x 3Nt
  VectorXd sigma;      // descending, rank-cut
  MatrixXd smallSide;  // eigenvectors of the Gram matrix, columns in sigma's order
  bool gramOfColumns;  // true: Gram = C^T C (small side = right vectors)
  double centredNorm2; // ||C||_F^2

  // Orthonormal basis (k columns) and the weights carrying sigma (k columns).
  void factors(std::size_t k, MatrixXd& basis, MatrixXd& weights) const
  {
    MatrixXd left, right; // C ~ left diag(sigma) right^T, both orthonormal
    if (gramOfColumns)
    {
      right = smallSide.leftCols(k);
      left = centred * right;
      for (std::size_t j = 0; j < k; ++j)
        left.col(j) /= sigma[j];
    }
    else
    {
      left = smallSide.leftCols(k);
      right = centred.transpose() * left;
      for (std::size_t j = 0; j < k; ++j)
        right.col(j) /= sigma[j];
    }
    if (layout == PcaLayout::Shapes)
    {
      basis = std::move(left);
      weights = right * sigma.head(k).asDiagonal();
    }
    else
    {
      basis = std::move(right);
      weights = left * sigma.head(k).asDiagonal();
    }
  }

  double truncationError(std::size_t k) const
  {
    const double kept = sigma.head(k).squaredNorm();
    return std::sqrt(std::max(0.0, centredNorm2 - kept));
  }
};

Decomposition decompose(const Eigen::Map<const MatrixXd>& A, PcaLayout layout)
{
  Decomposition d;
  d.layout = layout;
  d.frames = static_cast<std::size_t>(A.cols());
  d.vertices = static_cast<std::size_t>(A.rows()) / 3;
  if (layout == PcaLayout::Shapes)
  {
    d.mean = A.rowwise().mean();
    d.centred = A.colwise() - d.mean;
  }
  else
  {
    // B(i, 3t + c) = A(3i + c, t): row i is vertex i's trajectory.
    MatrixXd B(d.vertices, 3 * d.frames);
    for (std::size_t t = 0; t < d.frames; ++t)
      for (std::size_t i = 0; i < d.vertices; ++i)
        for (int c = 0; c < 3; ++c)
          B(i, 3 * t + c) = A(3 * i + c, t);
    d.mean = B.colwise().mean().transpose();
    B.rowwise() -= d.mean.transpose();
    d.centred = std::move(B);
  }
  d.centredNorm2 = d.centred.squaredNorm();
  d.gramOfColumns = d.centred.cols() <= d.centred.rows();
  const Eigen::Index side = d.gramOfColumns ? d.centred.cols() : d.centred.rows();
  MatrixXd gram = MatrixXd::Zero(side, side);
  if (d.gramOfColumns)
    gram.selfadjointView<Eigen::Lower>().rankUpdate(d.centred.transpose());
  else
    gram.selfadjointView<Eigen::Lower>().rankUpdate(d.centred);
  Eigen::SelfAdjointEigenSolver<MatrixXd> eigen(gram.selfadjointView<Eigen::Lower>());
  const VectorXd& values = eigen.eigenvalues(); // ascending
  const double largest = std::sqrt(std::max(0.0, values[side - 1]));
  std::size_t rank = 0;
  for (Eigen::Index j = side - 1; j >= 0; --j)
    if (std::sqrt(std::max(0.0, values[j])) > RankCut * largest && largest > 0)
      ++rank;
    else
      break;
  d.sigma.resize(rank);
  d.smallSide.resize(side, rank);
  for (std::size_t j = 0; j < rank; ++j)
  {
    d.sigma[j] = std::sqrt(values[side - 1 - j]);
    d.smallSide.col(j) = eigen.eigenvectors().col(side - 1 - j);
  }
  return d;
}

// ---------------------------------------------------------------------------------------------
// Integer sequences: order-0/1/2 prediction along a stride, zigzag varints.

void putVarint(std::vector<std::uint8_t>& out, std::uint64_t v)
{
  while (v >= 0x80)
  {
    out.push_back(static_cast<std::uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<std::uint8_t>(v));
}

std::uint64_t zigzag(std::int64_t v)
{
  return (static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63);
}
std::int64_t unzigzag(std::uint64_t v)
{
  return static_cast<std::int64_t>(v >> 1) ^ -static_cast<std::int64_t>(v & 1);
}

// For each vertex, its mesh neighbours with a smaller index: the values a decoder going through
// the vertices in order already has, so a per-vertex sequence can be predicted from them.
struct EarlierNeighbours
{
  EarlierNeighbours(const std::vector<std::int64_t>& triangles, std::size_t vertices)
  {
    std::vector<std::pair<std::size_t, std::size_t>> edges; // (later, earlier)
    edges.reserve(triangles.size());
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
      for (int e = 0; e < 3; ++e)
      {
        const auto a = static_cast<std::size_t>(triangles[t + e]);
        const auto b = static_cast<std::size_t>(triangles[t + (e + 1) % 3]);
        if (a != b)
          edges.emplace_back(std::max(a, b), std::min(a, b));
      }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    start.assign(vertices + 1, 0);
    for (const auto& e : edges)
      ++start[e.first + 1];
    for (std::size_t v = 0; v < vertices; ++v)
      start[v + 1] += start[v];
    index.reserve(edges.size());
    for (const auto& e : edges)
      index.push_back(e.second);
  }
  std::vector<std::size_t> start; // neighbours of v: index[start[v] .. start[v + 1])
  std::vector<std::size_t> index;
};

// Prediction orders: 0 none, 1 the value one stride back, 2 linear from two strides back,
// 3 (per-vertex sequences only) the rounded mean of the same coordinate at the vertex's
// earlier mesh neighbours, falling back to order 1 for a vertex without any.
constexpr int MeshOrder = 3;

// Two's-complement sum and difference without overflow (a corrupt file may hold any integers; its
// values are refused later by their range checks). Equal to + and - whenever those do not
// overflow, so valid files decode bit for bit as before.
std::int64_t wrappingSum(std::int64_t a, std::int64_t b)
{
  return static_cast<std::int64_t>(static_cast<std::uint64_t>(a) + static_cast<std::uint64_t>(b));
}

std::int64_t wrappingDifference(std::int64_t a, std::int64_t b)
{
  return static_cast<std::int64_t>(static_cast<std::uint64_t>(a) - static_cast<std::uint64_t>(b));
}

std::int64_t predicted(const std::int64_t* v, std::size_t i, std::size_t stride, int order,
                       const EarlierNeighbours* mesh)
{
  if (order == MeshOrder)
  {
    const std::size_t vertex = i / stride, c = i % stride;
    const std::size_t first = mesh->start[vertex], last = mesh->start[vertex + 1];
    if (last > first)
    {
      std::int64_t sum = 0;
      for (std::size_t n = first; n < last; ++n)
        sum = wrappingSum(sum, v[mesh->index[n] * stride + c]);
      return std::llround(static_cast<double>(sum) / static_cast<double>(last - first));
    }
    order = 1;
  }
  if (order == 0 || i < stride)
    return 0;
  if (order == 1 || i < 2 * stride)
    return v[i - stride];
  return wrappingDifference(wrappingSum(v[i - stride], v[i - stride]), v[i - 2 * stride]);
}

// `mesh` is given for sequences of `stride` values per vertex, which may then use MeshOrder.
void putSequence(std::vector<std::uint8_t>& out, const std::int64_t* v, std::size_t count,
                 std::size_t stride, const EarlierNeighbours* mesh = nullptr)
{
  int best = 0;
  double bestCost = std::numeric_limits<double>::infinity();
  for (int order = 0; order <= (mesh ? MeshOrder : 2); ++order)
  {
    double cost = 0;
    for (std::size_t i = 0; i < count; ++i)
      cost +=
          std::log2(1.0 + static_cast<double>(zigzag(v[i] - predicted(v, i, stride, order, mesh))));
    if (cost < bestCost)
    {
      bestCost = cost;
      best = order;
    }
  }
  out.push_back(static_cast<std::uint8_t>(best));
  for (std::size_t i = 0; i < count; ++i)
    putVarint(out, zigzag(v[i] - predicted(v, i, stride, best, mesh)));
}

class ByteReader
{
public:
  ByteReader(const std::uint8_t* data, std::size_t size, std::string what)
      : Data(data), Size(size), What(std::move(what))
  {
  }
  [[noreturn]] void fail(const std::string& why) const
  {
    throw std::runtime_error(What + ": " + why);
  }
  std::uint8_t byte()
  {
    if (Position >= Size)
      fail("truncated");
    return Data[Position++];
  }
  std::uint64_t varint()
  {
    std::uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7)
    {
      const std::uint8_t b = byte();
      v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
      if (!(b & 0x80))
        return v;
    }
    fail("malformed number");
  }
  template <typename T>
  T raw()
  {
    if (Size - Position < sizeof(T))
      fail("truncated");
    T v;
    std::memcpy(&v, Data + Position, sizeof(T));
    Position += sizeof(T);
    return v;
  }
  void sequence(std::int64_t* v, std::size_t count, std::size_t stride,
                const EarlierNeighbours* mesh = nullptr)
  {
    const int order = byte();
    if (order > (mesh ? MeshOrder : 2))
      fail("unknown prediction order " + std::to_string(order));
    for (std::size_t i = 0; i < count; ++i)
      v[i] = wrappingSum(unzigzag(varint()), predicted(v, i, stride, order, mesh));
  }
  std::size_t position() const { return Position; }
  std::size_t remaining() const { return Size - Position; }

private:
  const std::uint8_t* Data;
  std::size_t Size, Position = 0;
  std::string What;
};

template <typename T>
void putRaw(std::vector<std::uint8_t>& out, T v)
{
  const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
  out.insert(out.end(), p, p + sizeof(T));
}

// Strides of the prediction, the same in both layouts: x y z interleaved in the mean and the
// basis (3: the same coordinate one frame or one vertex back), one value per row in the weights.
constexpr std::size_t MeanStride = 3, BasisStride = 3, WeightStride = 1;

// The per-vertex parts: the mean and the basis in the shape layout, the weights in the
// trajectory layout. They may be predicted from mesh neighbours; the others run along time.
void putGeometry(std::vector<std::uint8_t>& out, const QuantisedPca& q,
                 const EarlierNeighbours& mesh)
{
  const PcaModel& m = q.model;
  const bool shapes = m.layout == PcaLayout::Shapes;
  const EarlierNeighbours* perVertex = shapes ? &mesh : nullptr;
  putSequence(out, q.meanIntegers.data(), q.meanIntegers.size(), MeanStride, perVertex);
  const std::size_t rows = static_cast<std::size_t>(m.basis.rows());
  for (std::size_t j = 0; j < m.components(); ++j)
    putSequence(out, q.basisIntegers.data() + j * rows, rows, BasisStride, perVertex);
  const std::size_t wrows = static_cast<std::size_t>(m.weights.rows());
  for (std::size_t j = 0; j < m.components(); ++j)
    putSequence(out, q.weightIntegers.data() + j * wrows, wrows, WeightStride,
                shapes ? nullptr : &mesh);
}

// zstd level of what is stored (19; 9 for big inputs, where 19 gets slow), and a quicker one
// that ranks the candidate component counts about as well.
int storedLevel(std::size_t bytes)
{
  return bytes < (8u << 20) ? 19 : 9;
}
constexpr int RankingLevel = 6;

std::vector<std::uint8_t> zstdCompress(const std::vector<std::uint8_t>& raw, int level = 0)
{
  std::vector<std::uint8_t> out(ZSTD_compressBound(raw.size()));
  if (level == 0)
    level = storedLevel(raw.size());
  const std::size_t n = ZSTD_compress(out.data(), out.size(), raw.data(), raw.size(), level);
  if (ZSTD_isError(n))
    throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
  out.resize(n);
  return out;
}

// Fixed-width bits of a sequence of integers: what quantised plain PCA would store.
double fixedWidthBits(const std::int64_t* v, std::size_t count)
{
  if (count == 0)
    return 0;
  const auto [lo, hi] = std::minmax_element(v, v + count);
  const double range = static_cast<double>(*hi - *lo) + 1;
  return std::ceil(std::log2(range)) * static_cast<double>(count) + 64; // + offset
}

// ---------------------------------------------------------------------------------------------
// Quantisation.

std::size_t meanRepeats(const Decomposition& d)
{
  return d.layout == PcaLayout::Shapes ? d.frames : d.vertices;
}

std::vector<std::int64_t> quantiseValues(const double* v, std::size_t n, double step,
                                         double* dequantised)
{
  std::vector<std::int64_t> q(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    q[i] = static_cast<std::int64_t>(std::llround(v[i] / step));
    dequantised[i] = static_cast<double>(q[i]) * step;
  }
  return q;
}

QuantisedPca quantise(const Decomposition& d, const MatrixXd& basis, const MatrixXd& weights,
                      double step)
{
  QuantisedPca q;
  PcaModel& m = q.model;
  m.layout = d.layout;
  m.vertices = d.vertices;
  m.frames = d.frames;
  const std::size_t k = static_cast<std::size_t>(basis.cols());
  q.step = step;
  q.meanStep = step / std::sqrt(static_cast<double>(meanRepeats(d)));
  m.mean.resize(d.mean.size());
  q.meanIntegers = quantiseValues(d.mean.data(), d.mean.size(), q.meanStep, m.mean.data());
  m.basis.resize(basis.rows(), basis.cols());
  m.weights.resize(weights.rows(), weights.cols());
  q.basisSteps.resize(k);
  q.basisIntegers.resize(basis.size());
  for (std::size_t j = 0; j < k; ++j)
  {
    q.basisSteps[j] = step / d.sigma[j];
    const auto ints =
        quantiseValues(basis.col(j).data(), basis.rows(), q.basisSteps[j], m.basis.col(j).data());
    std::copy(ints.begin(), ints.end(), q.basisIntegers.begin() + j * basis.rows());
  }
  q.weightIntegers = quantiseValues(weights.data(), weights.size(), step, m.weights.data());
  return q;
}

// ||X - X'||^2 of a quantised model in the KG search, without reconstructing the sequence.
// In both layouts the data, in the model's orientation, is X = m 1^T + B W^T + R (B the
// orthonormal basis, W = C^T B, R the truncation residual: B^T R = 0, R 1 = 0, ||R||^2 from
// the singular values), and the model is X' = m_q 1^T + B_q W_q^T. Then
// X' - X = D - R with D = (m_q - m) 1^T + (B_q - B) W_q^T + B (W_q - W)^T, and
// ||X' - X||^2 = ||D||^2 + ||R||^2 - 2 tr(W_q (B_q - B)^T R). The last term, quantisation noise
// against the residual, is left out (its mean is 0); the search checks its final step on the
// actual reconstruction. ||D||^2 = tr((P^T P)(Q^T Q)) with D = P Q^T, on k x k blocks.
double estimatedError2(const MatrixXd& basis, const MatrixXd& weights, const VectorXd& mean,
                       const PcaModel& q, double residual2)
{
  const Eigen::Index k = basis.cols();
  MatrixXd P(basis.rows(), 1 + 2 * k), Q(weights.rows(), 1 + 2 * k);
  P.col(0) = q.mean - mean;
  P.middleCols(1, k) = q.basis - basis;
  P.rightCols(k) = basis;
  Q.col(0).setOnes();
  Q.middleCols(1, k) = q.weights;
  Q.rightCols(k) = q.weights - weights;
  MatrixXd gp = MatrixXd::Zero(1 + 2 * k, 1 + 2 * k), gq = gp;
  gp.selfadjointView<Eigen::Lower>().rankUpdate(P.transpose());
  gq.selfadjointView<Eigen::Lower>().rankUpdate(Q.transpose());
  const MatrixXd fp = gp.selfadjointView<Eigen::Lower>(), fq = gq.selfadjointView<Eigen::Lower>();
  return fp.cwiseProduct(fq).sum() + residual2;
}

struct Errors
{
  double kg, max;
};

Errors errorsOf(const Eigen::Map<const MatrixXd>& A, const PcaModel& m)
{
  const MatrixXd approx = m.reconstruct();
  return {karniGotsmanError(A, approx), maxVertexError(A, approx)};
}

double measured(const Errors& e, PcaErrorMeasure measure, double diagonal)
{
  return measure == PcaErrorMeasure::KarniGotsman ? e.kg : e.max / diagonal;
}

void validateFinite(const double* p, std::size_t n)
{
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(p[i]))
      throw std::invalid_argument("position " + std::to_string(i / 3) + " is not finite");
}

} // namespace

double centroidSpread(const Eigen::Ref<const MatrixXd>& A)
{
  double spread = 0;
  for (Eigen::Index t = 0; t < A.cols(); ++t)
  {
    const auto frame = A.col(t).reshaped(3, A.rows() / 3);
    const Eigen::Vector3d centroid = frame.rowwise().mean();
    spread += (frame.colwise() - centroid).squaredNorm();
  }
  return std::sqrt(spread);
}

// -----------------------------------------------------------------------------------------------

void PcaModel::frame(std::size_t t, double* positions) const
{
  if (t >= frames)
    throw std::out_of_range("frame " + std::to_string(t) + " of " + std::to_string(frames));
  Eigen::Map<VectorXd> out(positions, 3 * vertices);
  if (layout == PcaLayout::Shapes)
  {
    out = mean + basis * weights.row(t).transpose();
    return;
  }
  // X_i[t] = m[t] + sum_j c_ij Y_j[t].
  const Eigen::Index k = basis.cols();
  for (int c = 0; c < 3; ++c)
  {
    const Eigen::Index row = static_cast<Eigen::Index>(3 * t + c);
    const VectorXd coordinate = weights * basis.row(row).head(k).transpose();
    for (std::size_t i = 0; i < vertices; ++i)
      out[3 * i + c] = mean[row] + coordinate[i];
  }
}

MatrixXd PcaModel::reconstruct() const
{
  MatrixXd all(3 * vertices, frames);
  for (std::size_t t = 0; t < frames; ++t)
    frame(t, all.col(t).data());
  return all;
}

double karniGotsmanError(const Eigen::Ref<const MatrixXd>& original,
                         const Eigen::Ref<const MatrixXd>& approx)
{
  const double spread = centroidSpread(original);
  const double error = (original - approx).norm();
  return spread > 0 ? 100 * error / spread : (error > 0 ? 100 : 0);
}

double maxVertexError(const Eigen::Ref<const MatrixXd>& original,
                      const Eigen::Ref<const MatrixXd>& approx)
{
  double worst = 0;
  for (Eigen::Index t = 0; t < original.cols(); ++t)
    for (Eigen::Index i = 0; i + 2 < original.rows(); i += 3)
      worst = std::max(worst,
                       (original.col(t).segment<3>(i) - approx.col(t).segment<3>(i)).squaredNorm());
  return std::sqrt(worst);
}

CompressedSequence compressSequence(const double* positions, std::size_t vertices,
                                    std::size_t frames, const PcaOptions& options,
                                    const std::vector<std::int64_t>& triangles,
                                    const std::vector<double>& times,
                                    const std::function<bool(double)>& progress)
{
  if (vertices == 0 || frames == 0)
    throw std::invalid_argument("the sequence has no " +
                                std::string(vertices == 0 ? "vertices" : "frames"));
  if (!(options.target > 0) || !std::isfinite(options.target) ||
      (options.measure == PcaErrorMeasure::KarniGotsman && options.target >= 100) ||
      (options.measure == PcaErrorMeasure::MaxVertexError && options.target >= 1))
    throw std::invalid_argument("error target " + std::to_string(options.target) +
                                " is out of range (KG: (0, 100) percent; max vertex error: "
                                "(0, 1) of the diagonal)");
  if (!times.empty() && times.size() != frames)
    throw std::invalid_argument("times: " + std::to_string(times.size()) + " values for " +
                                std::to_string(frames) + " frames");
  for (std::int64_t index : triangles)
    if (index < 0 || static_cast<std::size_t>(index) >= vertices)
      throw std::invalid_argument("triangle index " + std::to_string(index) + " out of range");
  if (triangles.size() % 3)
    throw std::invalid_argument("triangles: not a multiple of 3 indices");
  validateFinite(positions, 3 * vertices * frames);
  const EarlierNeighbours mesh(triangles, vertices);
  auto report = [&](double fraction)
  {
    if (progress && !progress(fraction))
      throw std::runtime_error("aborted");
  };

  const Eigen::Map<const MatrixXd> A(positions, 3 * vertices, frames);
  const Decomposition d = decompose(A, options.layout);
  report(0.3);
  const Eigen::Vector3d lo = A.reshaped(3, vertices * frames).rowwise().minCoeff();
  const Eigen::Vector3d hi = A.reshaped(3, vertices * frames).rowwise().maxCoeff();
  const double diagonal = (hi - lo).norm();
  const std::size_t rank = static_cast<std::size_t>(d.sigma.size());
  const double spreadNorm = centroidSpread(A); // KG's denominator
  // The truncation error alone, as the target measures it.
  auto truncated = [&](std::size_t k)
  {
    if (options.measure == PcaErrorMeasure::KarniGotsman)
      return spreadNorm > 0 ? 100 * d.truncationError(k) / spreadNorm : 0.0;
    MatrixXd basis, weights;
    d.factors(k, basis, weights);
    PcaModel m{d.layout, d.vertices, d.frames, d.mean, basis, weights};
    return measured(errorsOf(A, m), options.measure, diagonal);
  };
  // Smallest k whose truncation error is under `limit` (a fraction of the target).
  auto smallestK = [&](double limit)
  {
    if (options.measure == PcaErrorMeasure::KarniGotsman)
    {
      // From the singular values: KG_k = 100 ||C - C_k|| / ||A - E(A)||.
      const double allowed = limit * options.target;
      std::size_t k = 0;
      if (!(spreadNorm > 0))
        return k;
      while (k < rank && 100 * d.truncationError(k) / spreadNorm > allowed)
        ++k;
      return k;
    }
    // The max error has no closed form: bisect on reconstructions (k = rank is exact).
    std::size_t lo = 0, hi = rank;
    while (lo < hi)
    {
      const std::size_t mid = (lo + hi) / 2;
      if (truncated(mid) <= limit * options.target)
        hi = mid;
      else
        lo = mid + 1;
    }
    return lo;
  };

  CompressedSequence out;
  out.triangles = triangles;
  out.times = times;
  if (out.times.empty())
    for (std::size_t t = 0; t < frames; ++t)
      out.times.push_back(static_cast<double>(t));

  std::vector<std::size_t> candidates;
  if (options.components > 0)
    candidates.push_back(std::min(options.components, rank));
  else if (!options.quantise)
    candidates.push_back(smallestK(1.0));
  else
  {
    const std::size_t first = smallestK(0.97), last = std::max(first, smallestK(0.5));
    const std::size_t stepK = std::max<std::size_t>(1, (last - first) / 10);
    for (std::size_t k = first; k <= last; k += stepK)
      candidates.push_back(k);
  }

  PcaReport best;
  QuantisedPca bestModel;
  std::vector<std::uint8_t> bestPayload;
  double bestBits = std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < candidates.size(); ++c)
  {
    report(0.3 + 0.65 * static_cast<double>(c) / static_cast<double>(candidates.size()));
    const std::size_t k = candidates[c];
    MatrixXd basis, weights;
    d.factors(k, basis, weights);
    QuantisedPca q;
    double bits = 0, plainBits = 0;
    std::vector<std::uint8_t> payload;
    if (!options.quantise)
    {
      q.model = PcaModel{d.layout, d.vertices, d.frames, d.mean, basis, weights};
      bits = 32.0 * static_cast<double>(d.mean.size() + basis.size() + weights.size());
      plainBits = bits;
    }
    else
    {
      // Quantisation step: the error budget left by truncation, spread over every stored
      // number (each adds ~q^2/12), then searched on the actual error.
      const double truncation = truncated(k);
      const double goal = truncation < options.target ? options.target : 1.01 * truncation;
      const double count = static_cast<double>(d.mean.size() + basis.size() + weights.size());
      double budget;
      if (options.measure == PcaErrorMeasure::KarniGotsman)
      {
        const double e2 =
            std::pow(goal * spreadNorm / 100, 2) - std::pow(truncation * spreadNorm / 100, 2);
        budget = std::sqrt(12 * std::max(e2, 0.0) / count);
      }
      else
        budget = (goal - truncation) * diagonal;
      if (!(budget > 0))
        budget = 1e-6 * diagonal;
      auto passesActually = [&](double step, QuantisedPca& result)
      {
        result = quantise(d, basis, weights, step);
        return measured(errorsOf(A, result.model), options.measure, diagonal) <= goal;
      };
      // KG: searched on the estimate (no reconstruction), the final step checked for real.
      const double residual2 = std::pow(d.truncationError(k), 2);
      auto passes = [&](double step, QuantisedPca& result)
      {
        if (options.measure != PcaErrorMeasure::KarniGotsman || !(spreadNorm > 0))
          return passesActually(step, result);
        result = quantise(d, basis, weights, step);
        const double e2 = estimatedError2(basis, weights, d.mean, result.model, residual2);
        return 100 * std::sqrt(std::max(0.0, e2)) / spreadNorm <= goal;
      };
      // Bracket the largest step that passes, then bisect (the error grows with the step).
      double good = 0, bad = 0, stepSize = budget;
      QuantisedPca trial;
      for (int i = 0; i < 40 && good == 0; ++i, stepSize *= 0.5)
        if (passes(stepSize, trial))
          good = stepSize;
        else
          bad = stepSize;
      if (good == 0)
        throw std::runtime_error("cannot meet the error target by quantisation");
      if (bad == 0)
      {
        bad = good * 2;
        for (int i = 0; i < 10 && passes(bad, trial); ++i)
        {
          good = bad;
          bad *= 2;
        }
      }
      for (int i = 0; i < 6; ++i)
      {
        const double middle = std::sqrt(good * bad);
        if (passes(middle, trial))
          good = middle;
        else
          bad = middle;
      }
      bool met = false;
      for (int i = 0; i < 60 && !(met = passesActually(good, q)); ++i)
        good *= 0.98; // the estimate left out a noise term: step back until it holds
      if (!met)
        throw std::runtime_error("cannot meet the error target by quantisation");
      std::vector<std::uint8_t> raw;
      putGeometry(raw, q, mesh);
      payload = zstdCompress(raw, candidates.size() > 1 ? RankingLevel : 0);
      bits = 8.0 * static_cast<double>(payload.size());
      plainBits = fixedWidthBits(q.meanIntegers.data(), q.meanIntegers.size());
      for (std::size_t j = 0; j < k; ++j)
        plainBits += fixedWidthBits(q.basisIntegers.data() + j * basis.rows(),
                                    static_cast<std::size_t>(basis.rows())) +
                     fixedWidthBits(q.weightIntegers.data() + j * weights.rows(),
                                    static_cast<std::size_t>(weights.rows()));
    }
    if (bits < bestBits)
    {
      bestBits = bits;
      bestModel = std::move(q);
      bestPayload = std::move(payload);
      const double vf = static_cast<double>(vertices * frames);
      best.components = k;
      best.bitsPerVertexFrame = bits / vf;
      best.quantisedPlainBits = plainBits / vf;
      best.payloadBytes = bestPayload.size();
    }
  }
  if (options.quantise && candidates.size() > 1)
  {
    // The winner as it is stored (the file's geometry section).
    std::vector<std::uint8_t> raw;
    putGeometry(raw, bestModel, mesh);
    bestPayload = zstdCompress(raw);
    best.payloadBytes = bestPayload.size();
    best.bitsPerVertexFrame =
        8.0 * static_cast<double>(bestPayload.size()) / static_cast<double>(vertices * frames);
  }
  const Errors e = errorsOf(A, bestModel.model);
  best.kgError = e.kg;
  best.maxError = e.max;
  best.diagonal = diagonal;
  best.maxErrorRelative = diagonal > 0 ? e.max / diagonal : 0;
  const double nt = static_cast<double>(frames), nv = static_cast<double>(vertices),
               ny = static_cast<double>(best.components);
  best.paperD0 = 3 * nt * nv;
  best.paperD1 = 3 * nt * ny + nv * ny;
  best.paperRatio = best.paperD1 > 0 ? best.paperD0 / best.paperD1 : 0;
  out.pca = std::move(bestModel);
  out.report = best;
  report(1.0);
  return out;
}

// -----------------------------------------------------------------------------------------------
// The file.

namespace
{

// A fuzzing build (Testing/Fuzz) computes the checksums but does not enforce them, so mutated
// inputs reach the decoder behind them.
#ifdef DP_FUZZING_BUILD
constexpr bool EnforceChecksums = false;
#else
constexpr bool EnforceChecksums = true;
#endif

std::uint32_t crc(const std::uint8_t* data, std::size_t size)
{
  uLong c = crc32(0L, Z_NULL, 0);
  while (size > 0)
  {
    const uInt chunk = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
    c = crc32(c, data, chunk);
    data += chunk;
    size -= chunk;
  }
  return static_cast<std::uint32_t>(c);
}

void putSection(std::vector<std::uint8_t>& out, const std::vector<std::uint8_t>& raw)
{
  const std::vector<std::uint8_t> packed = zstdCompress(raw);
  putRaw<std::uint64_t>(out, raw.size());
  putRaw<std::uint64_t>(out, packed.size());
  putRaw<std::uint32_t>(out, crc(packed.data(), packed.size()));
  out.insert(out.end(), packed.begin(), packed.end());
}

std::vector<std::uint8_t> getSection(ByteReader& in, const std::uint8_t* bytes,
                                     const std::string& what, std::uint64_t limit)
{
  const auto rawSize = in.raw<std::uint64_t>();
  const auto packedSize = in.raw<std::uint64_t>();
  const auto expected = in.raw<std::uint32_t>();
  if (packedSize > in.remaining())
    in.fail(what + " is truncated (" + std::to_string(in.remaining()) + " of " +
            std::to_string(packedSize) + " bytes)");
  if (rawSize > limit)
    in.fail(what + " claims " + std::to_string(rawSize) + " bytes, more than its counts allow");
  // A zstd block holds at most 128 KiB and takes at least 4 bytes (an RLE block): no frame
  // expands more than that, so a larger claim is refused before it is allocated.
  if (rawSize > 32768 * packedSize + 131072)
    in.fail(what + " claims " + std::to_string(rawSize) + " bytes from " +
            std::to_string(packedSize) + " packed bytes, more than zstd can expand to");
  const std::uint8_t* packed = bytes + in.position();
  if (crc(packed, packedSize) != expected && EnforceChecksums)
    in.fail(what + ": checksum mismatch (the file is corrupt)");
  std::vector<std::uint8_t> raw(rawSize);
  const std::size_t n = ZSTD_decompress(raw.data(), raw.size(), packed, packedSize);
  if (ZSTD_isError(n) || n != rawSize)
    in.fail(what + ": cannot be decompressed");
  for (std::uint64_t i = 0; i < packedSize; ++i)
    in.byte();
  return raw;
}

} // namespace

std::vector<std::uint8_t> encodeCompressedSequence(const CompressedSequence& s)
{
  const QuantisedPca& q = s.pca;
  const PcaModel& m = q.model;
  if (q.step <= 0)
    throw std::invalid_argument("only a quantised sequence can be written (quantise = true)");
  std::vector<std::uint8_t> header;
  putRaw<std::uint8_t>(header, static_cast<std::uint8_t>(m.layout));
  putRaw<std::uint64_t>(header, m.vertices);
  putRaw<std::uint64_t>(header, m.frames);
  putRaw<std::uint64_t>(header, m.components());
  putRaw<std::uint64_t>(header, s.triangles.size() / 3);
  putRaw<double>(header, q.step);
  putRaw<double>(header, q.meanStep);
  for (double v : q.basisSteps)
    putRaw<double>(header, v);
  for (std::size_t t = 0; t < m.frames; ++t)
    putRaw<double>(header, t < s.times.size() ? s.times[t] : static_cast<double>(t));

  std::vector<std::uint8_t> out(Magic, Magic + sizeof(Magic));
  putRaw<std::uint32_t>(out, FormatVersion);
  putRaw<std::uint64_t>(out, header.size());
  out.insert(out.end(), header.begin(), header.end());
  putRaw<std::uint32_t>(out, crc(header.data(), header.size()));

  std::vector<std::uint8_t> connectivity;
  putSequence(connectivity, s.triangles.data(), s.triangles.size(), 3);
  putSection(out, connectivity);
  std::vector<std::uint8_t> geometry;
  putGeometry(geometry, q, EarlierNeighbours(s.triangles, m.vertices));
  putSection(out, geometry);
  return out;
}

CompressedSequence decodeCompressedSequence(const std::uint8_t* bytes, std::size_t size,
                                            const std::string& name)
{
  ByteReader in(bytes, size, name);
  if (size < sizeof(Magic) || std::memcmp(bytes, Magic, sizeof(Magic)) != 0)
    in.fail("not a DynamicPoints compressed sequence (.dpz)");
  for (std::size_t i = 0; i < sizeof(Magic); ++i)
    in.byte();
  const auto version = in.raw<std::uint32_t>();
  if (version != FormatVersion)
    in.fail("format version " + std::to_string(version) +
            " is not supported (this reader: " + std::to_string(FormatVersion) + ")");
  const auto headerSize = in.raw<std::uint64_t>();
  if (headerSize > in.remaining())
    in.fail("header truncated");
  const std::uint8_t* headerBytes = bytes + in.position();
  ByteReader header(headerBytes, headerSize, name + " (header)");
  for (std::uint64_t i = 0; i < headerSize; ++i)
    in.byte();
  if (in.raw<std::uint32_t>() != crc(headerBytes, headerSize) && EnforceChecksums)
    in.fail("header checksum mismatch (the file is corrupt)");

  CompressedSequence s;
  QuantisedPca& q = s.pca;
  PcaModel& m = q.model;
  const auto layout = header.raw<std::uint8_t>();
  if (layout > 1)
    header.fail("unknown layout " + std::to_string(layout));
  m.layout = static_cast<PcaLayout>(layout);
  const auto nv = header.raw<std::uint64_t>();
  const auto nt = header.raw<std::uint64_t>();
  const auto k = header.raw<std::uint64_t>();
  const auto nTriangles = header.raw<std::uint64_t>();
  const std::uint64_t limit = std::uint64_t{1} << 40;
  if (nv == 0 || nt == 0 || nv > limit || nt > limit || nv * nt > limit || k > 3 * nt ||
      k > 3 * nv || nTriangles > limit)
    header.fail("implausible counts (vertices " + std::to_string(nv) + ", frames " +
                std::to_string(nt) + ", components " + std::to_string(k) + ")");
  if (header.remaining() != 8 * (2 + k + nt))
    header.fail("header length does not match its counts");
  m.vertices = nv;
  m.frames = nt;
  q.step = header.raw<double>();
  q.meanStep = header.raw<double>();
  if (!(q.step > 0) || !(q.meanStep > 0) || !std::isfinite(q.step) || !std::isfinite(q.meanStep))
    header.fail("invalid quantisation step");
  q.basisSteps.resize(k);
  for (double& v : q.basisSteps)
  {
    v = header.raw<double>();
    if (!(v > 0) || !std::isfinite(v))
      header.fail("invalid basis step");
  }
  s.times.resize(nt);
  for (double& v : s.times)
  {
    v = header.raw<double>();
    if (!std::isfinite(v))
      header.fail("a time value is not finite");
  }

  // Each varint takes at most 10 bytes, each sequence one more for its order.
  const std::uint64_t meanCount = m.layout == PcaLayout::Shapes ? 3 * nv : 3 * nt;
  const std::uint64_t basisRows = m.layout == PcaLayout::Shapes ? 3 * nv : 3 * nt;
  const std::uint64_t weightRows = m.layout == PcaLayout::Shapes ? nt : nv;
  {
    const std::vector<std::uint8_t> raw =
        getSection(in, bytes, "connectivity", 10 * 3 * nTriangles + 1);
    ByteReader c(raw.data(), raw.size(), name + " (connectivity)");
    if (raw.size() < 3 * nTriangles) // every index takes at least a byte
      c.fail("holds " + std::to_string(raw.size()) + " bytes for " +
             std::to_string(3 * nTriangles) + " indices");
    s.triangles.resize(3 * nTriangles);
    c.sequence(s.triangles.data(), s.triangles.size(), 3);
    if (c.remaining() != 0)
      c.fail("unexpected bytes after the triangles");
    for (std::int64_t v : s.triangles)
      if (v < 0 || static_cast<std::uint64_t>(v) >= nv)
        c.fail("triangle index " + std::to_string(v) + " out of range");
  }
  {
    const std::uint64_t numbers = meanCount + k * (basisRows + weightRows);
    const std::vector<std::uint8_t> raw =
        getSection(in, bytes, "geometry", 10 * numbers + 1 + 2 * k);
    ByteReader g(raw.data(), raw.size(), name + " (geometry)");
    if (raw.size() < numbers) // every number takes at least a byte
      g.fail("holds " + std::to_string(raw.size()) + " bytes for " + std::to_string(numbers) +
             " numbers");
    const EarlierNeighbours mesh(s.triangles, nv);
    const bool shapes = m.layout == PcaLayout::Shapes;
    const EarlierNeighbours* perVertex = shapes ? &mesh : nullptr;
    q.meanIntegers.resize(meanCount);
    g.sequence(q.meanIntegers.data(), meanCount, MeanStride, perVertex);
    q.basisIntegers.resize(k * basisRows);
    for (std::uint64_t j = 0; j < k; ++j)
      g.sequence(q.basisIntegers.data() + j * basisRows, basisRows, BasisStride, perVertex);
    q.weightIntegers.resize(k * weightRows);
    for (std::uint64_t j = 0; j < k; ++j)
      g.sequence(q.weightIntegers.data() + j * weightRows, weightRows, WeightStride,
                 shapes ? nullptr : &mesh);
    if (g.remaining() != 0)
      g.fail("unexpected bytes after the weights");
  }
  if (in.remaining() != 0)
    in.fail("unexpected bytes after the last section");

  m.mean.resize(meanCount);
  for (std::uint64_t i = 0; i < meanCount; ++i)
    m.mean[i] = static_cast<double>(q.meanIntegers[i]) * q.meanStep;
  m.basis.resize(basisRows, k);
  for (std::uint64_t j = 0; j < k; ++j)
    for (std::uint64_t i = 0; i < basisRows; ++i)
      m.basis(i, j) = static_cast<double>(q.basisIntegers[j * basisRows + i]) * q.basisSteps[j];
  m.weights.resize(weightRows, k);
  for (std::uint64_t i = 0; i < k * weightRows; ++i)
    m.weights.data()[i] = static_cast<double>(q.weightIntegers[i]) * q.step;
  if (!m.mean.allFinite() || !m.basis.allFinite() || !m.weights.allFinite())
    in.fail("values out of range");
  s.report.components = k;
  return s;
}

void writeCompressedSequence(const std::string& path, const CompressedSequence& sequence)
{
  const std::vector<std::uint8_t> bytes = encodeCompressedSequence(sequence);
  // Write beside and rename, so a failed write never leaves a half file under the name.
  const std::string partial = path + ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out)
      throw std::runtime_error(path + ": cannot open for writing");
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    if (!out)
      throw std::runtime_error(path + ": write failed");
  }
  if (std::rename(partial.c_str(), path.c_str()) != 0)
    throw std::runtime_error(path + ": cannot rename " + partial + " into place");
}

CompressedSequence readCompressedSequence(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error(path + ": cannot open");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  return decodeCompressedSequence(bytes.data(), bytes.size(), path);
}

} // namespace dp

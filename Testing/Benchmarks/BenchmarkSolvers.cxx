// SPDX-License-Identifier: BSD-3-Clause
// Benchmark: the coarse level's linear solve. The node system of a deformation graph (6 unknowns
// a node, the graph's edges as its pattern) factorised and solved by the block Cholesky the
// tracker uses (support::BlockCholeskyOf<6>) and by Eigen's scalar SimplicialLDLT, in the same
// run, interleaved, on the same matrices: medians of --repeats, their ratio, and both solutions'
// residuals. The graph is sampled on frame 0 of a mesh sequence (--data/--sequence; the built-in
// tube by default) with --nodes nodes (a 1000-vertex template gets 200); the matrix's values are
// random, symmetric positive definite, with the graph's pattern (the fill, so the work, depends
// on the pattern only).
#include "BenchmarkSequences.h"
#include "BenchmarkUtilities.h"
#include "CommandLine.h"

#include "dp/support/BlockCholesky.h"
#include "dp/track/DeformationGraph.h"

#include <Eigen/SparseCholesky>

#include <cstdio>
#include <iostream>
#include <random>
#include <thread>

namespace
{
using namespace dp::bench;

const char* Usage = "Usage: BenchmarkSolvers [--data DIR] [--sequence NAME|tube] "
                    "[--nodes N[,N...]] [--repeats R]\n";

// Sums of w u u^T over the pattern's pairs (u spanning both nodes) plus a small diagonal.
void fillSpd(dp::support::BlockSparseMatrixOf<6>& m,
             const std::vector<std::array<std::int64_t, 2>>& pairs, std::mt19937_64& rng)
{
  std::normal_distribution<double> value;
  m.setZero();
  for (const auto& p : pairs)
  {
    Eigen::Matrix<double, 6, 1> u, v;
    for (int i = 0; i < 6; ++i)
    {
      u[i] = value(rng);
      v[i] = value(rng);
    }
    m.addOuter(p[0], p[0], u.data(), u.data(), 1.0);
    m.addOuter(p[1], p[1], v.data(), v.data(), 1.0);
    m.addOuter(p[0], p[1], u.data(), v.data(), 1.0);
  }
  m.addToDiagonal(Eigen::VectorXd::Constant(m.matrix().rows(), 0.1));
}

double residual(const dp::support::BlockSparseMatrixOf<6>& m, const Eigen::VectorXd& x,
                const Eigen::VectorXd& b)
{
  return (m.matrix().selfadjointView<Eigen::Lower>() * x - b).norm() / b.norm();
}

void compare(const dp::AnimatedMesh& mesh, std::size_t nodes, std::size_t repeats)
{
  const std::vector<double> rest = mesh.positions(0);
  const dp::TriangleMesh triangles(mesh.triangles(), mesh.numberOfVertices());
  const dp::DeformationGraph graph(triangles, rest.data(), nodes, 4);
  dp::support::BlockSparseMatrixOf<6> m(graph.numberOfNodes(), graph.edges());
  std::mt19937_64 rng(1);
  fillSpd(m, graph.edges(), rng);
  const Eigen::VectorXd b = Eigen::VectorXd::Random(m.matrix().rows());

  dp::support::BlockCholeskyOf<6> blocks;
  Eigen::SimplicialLDLT<dp::support::BlockSparseMatrixOf<6>::Matrix, Eigen::Lower> scalar;
  blocks.analyse(m);
  scalar.analyzePattern(m.matrix());
  std::vector<double> blockMs, scalarMs;
  Eigen::VectorXd xBlocks, xScalar;
  bool ok = true;
  for (std::size_t r = 0; r < repeats; ++r)
  {
    double start = now();
    ok = blocks.factorise(m) && ok;
    xBlocks = blocks.solve(b);
    blockMs.push_back(1e3 * (now() - start));
    start = now();
    scalar.factorize(m.matrix());
    xScalar = scalar.solve(b);
    scalarMs.push_back(1e3 * (now() - start));
    ok = ok && scalar.info() == Eigen::Success;
  }
  const double blockMedian = median(blockMs), scalarMedian = median(scalarMs);
  std::printf("%8zu %9lld %11zu %12.3f %12.3f %8.2fx %12.1e %12.1e%s\n", graph.numberOfNodes(),
              static_cast<long long>(m.matrix().rows()), blocks.offDiagonalBlocks(), scalarMedian,
              blockMedian, scalarMedian / blockMedian, residual(m, xScalar, b),
              residual(m, xBlocks, b), ok ? "" : "  (a factorisation failed)");
}
} // namespace

int main(int argc, char** argv)
{
  using namespace dp::cli;
  std::string data = "../shared/data", sequence = "tube";
  std::vector<std::size_t> nodes = {100, 200, 400, 600};
  std::size_t repeats = 30;
  try
  {
    for (int i = 1; i < argc; ++i)
    {
      const std::string arg = argv[i];
      if (arg == "--data")
        data = optionValue(argc, argv, i);
      else if (arg == "--sequence")
        sequence = optionValue(argc, argv, i);
      else if (arg == "--repeats")
        repeats = parseCount(arg, optionValue(argc, argv, i), 1, 100000);
      else if (arg == "--nodes")
      {
        nodes.clear();
        for (const std::string& item : splitList(optionValue(argc, argv, i)))
          nodes.push_back(parseCount(arg, item, 2, 1000000));
      }
      else
      {
        std::cout << Usage;
        return arg == "-h" || arg == "--help" ? 0 : 2;
      }
    }
    const auto mesh = loadAnimation(data, sequence);
    if (!mesh)
      return 1;
    std::printf("machine: %s, %u hardware threads (the solves are serial); %s, %zu vertices; "
                "medians of %zu factorise+solve, interleaved\n",
                cpuModel().c_str(), std::thread::hardware_concurrency(), sequence.c_str(),
                mesh->numberOfVertices(), repeats);
    std::printf("%8s %9s %11s %12s %12s %9s %12s %12s\n", "nodes", "unknowns", "fill blocks",
                "Eigen LDLT", "blocks ms", "ratio", "Eigen resid", "blocks resid");
    for (std::size_t n : nodes)
      compare(*mesh, n, repeats);
  }
  catch (const UsageError& e)
  {
    std::cerr << e.what() << "\n" << Usage;
    return 2;
  }
  catch (const std::exception& e)
  {
    std::cerr << "BenchmarkSolvers: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

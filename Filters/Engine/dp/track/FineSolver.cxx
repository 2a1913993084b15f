// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/FineSolver.h"

#include "dp/geometry/TriangleMesh.h"

namespace dp
{

namespace
{

// Every vertex pair a term of the fine level may couple: the cloth's (edges, hinges) include the
// points -> mesh term's (edges).
std::vector<std::array<std::int64_t, 2>> finePairs(const TriangleMesh& mesh)
{
  std::vector<std::array<std::int64_t, 2>> pairs(mesh.edges().begin(), mesh.edges().end());
  for (const auto& h : mesh.hinges())
    pairs.push_back({h[2], h[3]});
  return pairs;
}

class GaussNewton : public FineSolver
{
public:
  explicit GaussNewton(const TriangleMesh& mesh) : Solver(mesh.numberOfVertices(), finePairs(mesh))
  {
  }
  int solve(std::vector<double>& x, const std::vector<EnergyTerm*>& terms,
            const DistanceTerm* distance, const SolveSettings& settings,
            std::vector<std::uint8_t>&) override
  {
    return Solver.solve(x, terms, distance, settings);
  }
  bool takesFewStepsAfterCoarseLevel() const override { return true; }

private:
  GaussNewtonSolver Solver;
};

class Lbfgs : public FineSolver
{
public:
  int solve(std::vector<double>& x, const std::vector<EnergyTerm*>& terms, const DistanceTerm*,
            const SolveSettings& settings, std::vector<std::uint8_t>&) override
  {
    return solveLbfgs(x, terms, settings);
  }
};

class SteepestDescent : public FineSolver
{
public:
  SteepestDescent(const TriangleMesh& mesh, double lengthScale, bool provisionalDetermination)
      : Mesh(mesh), LengthScale(lengthScale), Provisional(provisionalDetermination)
  {
  }
  int solve(std::vector<double>& x, const std::vector<EnergyTerm*>& terms, const DistanceTerm*,
            const SolveSettings& settings, std::vector<std::uint8_t>& frozen) override
  {
    return solveSteepestDescent(x, terms, Mesh, LengthScale, settings,
                                Provisional ? &frozen : nullptr);
  }

private:
  const TriangleMesh& Mesh;
  double LengthScale;
  bool Provisional;
};

} // namespace

std::unique_ptr<FineSolver> FineSolver::make(const TrackerOptions& options,
                                             const TriangleMesh& mesh, double lengthScale)
{
  switch (options.solver)
  {
  case TrackerSolver::LBFGS:
    return std::make_unique<Lbfgs>();
  case TrackerSolver::SteepestDescent:
    return std::make_unique<SteepestDescent>(mesh, lengthScale, options.provisionalDetermination);
  default:
    return std::make_unique<GaussNewton>(mesh);
  }
}

} // namespace dp

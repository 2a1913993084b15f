// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/TracePreconditioner.h"

// Eigen's MetisSupport uses std::cerr without including <iostream>.
#include <iostream>

#include <Eigen/CholmodSupport>
#include <Eigen/MetisSupport>
#include <Eigen/SparseCholesky>

#include <dlfcn.h>

namespace dp
{
namespace
{
using Matrix = support::BlockSparseMatrix::Matrix;
using Coordinates = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// Debian's CHOLMOD parallelises its supernodal assembly with OpenMP at a fixed 4 threads
// (num_threads clause), whatever the machine has; on 2 cores, beside TBB's workers, that cost the
// fine level 40 % (scaling tube, 30 000 vertices). With OpenMP's dynamic adjustment on, the
// runtime gives a region no more threads than there are idle cores. The setting is the calling
// thread's own (restored on leaving); the runtime is looked up rather than linked, as CHOLMOD
// brings it (nothing to do when it does not).
class IdleCoresOnly
{
public:
  IdleCoresOnly()
  {
    if (runtime().set && runtime().get)
    {
      Before = runtime().get();
      runtime().set(1);
    }
  }
  ~IdleCoresOnly()
  {
    if (runtime().set && runtime().get)
      runtime().set(Before);
  }
  IdleCoresOnly(const IdleCoresOnly&) = delete;
  IdleCoresOnly& operator=(const IdleCoresOnly&) = delete;

private:
  struct Runtime
  {
    void (*set)(int) = nullptr;
    int (*get)() = nullptr;
  };
  static const Runtime& runtime()
  {
    static const Runtime r{reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "omp_set_dynamic")),
                           reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, "omp_get_dynamic"))};
    return r;
  }
  int Before = 0;
};
} // namespace

class TracePreconditioner::Factorisation
{
public:
  virtual ~Factorisation() = default;
  virtual bool factorise(const Matrix& P) = 0;
  virtual Eigen::VectorXd apply(const Eigen::VectorXd& r) const = 0;
  virtual bool supernodal() const = 0;
};

namespace
{
// Factorises P with an Eigen sparse solver (its interface: analyzePattern, factorize, info),
// analysing the pattern on the first call only.
template <typename Solver>
bool factoriseOnPattern(Solver& solver, bool& analysed, const Matrix& P)
{
  if (!analysed)
  {
    solver.analyzePattern(P);
    analysed = true;
  }
  solver.factorize(P);
  return solver.info() == Eigen::Success;
}

// Eigen's simplicial LDL^T, P = Q^T L D L^T Q, swept by hand so that the three coordinates of a
// vertex go through L's columns together: Eigen's own solve visits L once per coordinate, and its
// transposed sweep over a column-major L ran three times slower than the forward one.
class SimplicialFactorisation final : public TracePreconditioner::Factorisation
{
public:
  bool factorise(const Matrix& P) override { return factoriseOnPattern(Ldlt, Analysed, P); }

  Eigen::VectorXd apply(const Eigen::VectorXd& r) const override
  {
    const auto& L =
        Ldlt.matrixL().nestedExpression(); // strictly lower: the unit diagonal is implied
    const Eigen::VectorXd& D = Ldlt.vectorD();
    const auto& permutation = Ldlt.permutationP().indices();
    const Eigen::Index n = r.size() / 3;
    const auto order = [&](Eigen::Index i) { return permutation.size() ? permutation[i] : i; };
    const int* starts = L.outerIndexPtr();
    const int* rows = L.innerIndexPtr();
    const double* values = L.valuePtr();
    const int* counts = L.innerNonZeroPtr(); // null when L is compressed
    const auto end = [&](Eigen::Index j) { return counts ? starts[j] + counts[j] : starts[j + 1]; };
    Eigen::VectorXd y(r.size());
    for (Eigen::Index i = 0; i < n; ++i)
      y.segment<3>(3 * order(i)) = r.segment<3>(3 * i);
    for (Eigen::Index j = 0; j < n; ++j) // L y' = y
    {
      const Eigen::Vector3d yj = y.segment<3>(3 * j);
      for (int p = starts[j]; p < end(j); ++p)
        y.segment<3>(3 * rows[p]) -= values[p] * yj;
    }
    for (Eigen::Index j = 0; j < n; ++j)
      y.segment<3>(3 * j) /= D[j];
    for (Eigen::Index j = n; j-- > 0;) // L^T y'' = y'
    {
      Eigen::Vector3d sum = y.segment<3>(3 * j);
      for (int p = starts[j]; p < end(j); ++p)
        sum -= values[p] * y.segment<3>(3 * rows[p]);
      y.segment<3>(3 * j) = sum;
    }
    Eigen::VectorXd z(r.size());
    for (Eigen::Index i = 0; i < n; ++i)
      z.segment<3>(3 * i) = y.segment<3>(3 * order(i));
    return z;
  }

  bool supernodal() const override { return false; }

private:
  Eigen::SimplicialLDLT<Matrix, Eigen::Lower, Eigen::MetisOrdering<int>> Ldlt;
  bool Analysed = false;
};

// CHOLMOD's supernodal LL^T in METIS's order; the three coordinates are three right-hand sides.
class SupernodalFactorisation final : public TracePreconditioner::Factorisation
{
public:
  SupernodalFactorisation()
  {
    Llt.cholmod().nmethods = 1;
    Llt.cholmod().method[0].ordering = CHOLMOD_METIS;
    Llt.cholmod().print = 0; // a failed factorisation is reported by factorise(), not on stderr
  }

  bool factorise(const Matrix& P) override
  {
    const IdleCoresOnly threads;
    return factoriseOnPattern(Llt, Analysed, P);
  }

  Eigen::VectorXd apply(const Eigen::VectorXd& r) const override
  {
    const IdleCoresOnly threads;
    const Eigen::Index n = r.size() / 3;
    const Eigen::MatrixXd Z =
        Llt.solve(Eigen::MatrixXd(Eigen::Map<const Coordinates>(r.data(), n, 3)));
    Eigen::VectorXd z(r.size());
    Eigen::Map<Coordinates>(z.data(), n, 3) = Z;
    return z;
  }

  bool supernodal() const override { return true; }

private:
  Eigen::CholmodSupernodalLLT<Matrix, Eigen::Lower> Llt;
  bool Analysed = false;
};
} // namespace

TracePreconditioner::TracePreconditioner(long size, Kind kind)
{
  const bool supernodal =
      kind == Kind::Supernodal || (kind == Kind::Automatic && size >= SupernodalFrom);
  if (supernodal)
    Impl = std::make_unique<SupernodalFactorisation>();
  else
    Impl = std::make_unique<SimplicialFactorisation>();
}

TracePreconditioner::~TracePreconditioner() = default;

bool TracePreconditioner::factorise(const Matrix& P)
{
  Factorised = Impl->factorise(P);
  return Factorised;
}

Eigen::VectorXd TracePreconditioner::apply(const Eigen::VectorXd& r) const
{
  return Impl->apply(r);
}

bool TracePreconditioner::factorised() const
{
  return Factorised;
}

bool TracePreconditioner::supernodal() const
{
  return Impl->supernodal();
}

} // namespace dp

// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/InternalEnergyTerm.h"

namespace dp
{

double InternalEnergyTerm::addModel(const double* x, support::BlockSparseMatrix& hessian,
                                    double* gradient) const
{
  const bool haveSlots = SlotsOf == &hessian;
  if (!haveSlots)
    Slots.clear();
  std::size_t next = 0;
  double energy = 0;
  Cloth.forEachTerm(x,
                    [&](const ClothTerm& t)
                    {
                      energy += t.energy;
                      for (int a = 0; a < t.count; ++a)
                      {
                        for (int k = 0; k < 3; ++k)
                          gradient[3 * t.vertex[a] + k] += t.weight * t.residual * t.gradient[a][k];
                        for (int b = a; b < t.count; ++b)
                        {
                          if (!haveSlots)
                            Slots.push_back(hessian.slotOf(t.vertex[a], t.vertex[b]));
                          hessian.addOuter(Slots[next++], t.gradient[a], t.gradient[b], t.weight);
                        }
                      }
                    });
  SlotsOf = &hessian;
  return energy;
}

void InternalEnergyTerm::couplings(std::vector<std::array<std::int64_t, 2>>& pairs) const
{
  const TriangleMesh& mesh = Cloth.mesh();
  pairs.insert(pairs.end(), mesh.edges().begin(), mesh.edges().end());
  for (const auto& h : mesh.hinges())
    pairs.push_back({h[2], h[3]});
}

} // namespace dp

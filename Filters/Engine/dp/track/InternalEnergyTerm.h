// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file InternalEnergyTerm.h
 * @brief The paper's E_int (ClothEnergy: stretch, shear, bend) as a term of the tracking
 *        energy. Its Gauss-Newton model is sum_terms k grad(r) grad(r)^T over the cloth's
 *        residuals; it couples the vertices of each edge and the two opposite vertices of each
 *        hinge.
 */
#pragma once

#include "dp/track/ClothEnergy.h"
#include "dp/track/EnergyTerm.h"

namespace dp
{

class InternalEnergyTerm : public EnergyTerm
{
public:
  explicit InternalEnergyTerm(const ClothEnergy& cloth) : Cloth(cloth) {}
  const char* name() const override { return "internal"; }
  double evaluate(const double* x, double* gradient) const override
  {
    return gradient ? Cloth.addGradient(x, gradient) : Cloth.value(x);
  }
  double addModel(const double* x, support::BlockSparseMatrix& hessian,
                  double* gradient) const override;
  void couplings(std::vector<std::array<std::int64_t, 2>>& pairs) const override;

private:
  const ClothEnergy& Cloth;
  // The blocks each cloth term's vertex pairs add to, in the order ClothEnergy visits them, for
  // the matrix they were found in (the pattern is fixed, so they are found once).
  mutable std::vector<support::BlockSparseMatrix::Slot> Slots;
  mutable const support::BlockSparseMatrix* SlotsOf = nullptr;
};

} // namespace dp

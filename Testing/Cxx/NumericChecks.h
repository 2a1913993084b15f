// SPDX-License-Identifier: BSD-3-Clause
// Helpers for the numerical tests: a randomly perturbed copy of a vector, and the check of an
// analytic gradient against central differences.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

namespace dp::test
{

/** x with every component moved by a uniform random amount in [-amount, amount]. */
inline std::vector<double> jiggle(const std::vector<double>& x, double amount, unsigned seed)
{
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-amount, amount);
  std::vector<double> y(x);
  for (double& v : y)
    v += u(rng);
  return y;
}

/** The analytic gradient of f (f(x, gradient or nullptr) returns the value and adds the
 *  gradient) against central differences at x: the largest difference, relative to the largest
 *  gradient component, must stay under `tolerance`. */
inline void expectGradientMatches(const std::function<double(const double*, double*)>& f,
                                  const std::vector<double>& x, double tolerance, double h = 1e-6)
{
  std::vector<double> g(x.size(), 0.0);
  f(x.data(), g.data());
  std::vector<double> y(x);
  double worst = 0, scale = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
  {
    y[i] = x[i] + h;
    const double fp = f(y.data(), nullptr);
    y[i] = x[i] - h;
    const double fm = f(y.data(), nullptr);
    y[i] = x[i];
    worst = std::max(worst, std::abs((fp - fm) / (2 * h) - g[i]));
    scale = std::max(scale, std::abs(g[i]));
  }
  ASSERT_GT(scale, 0);
  EXPECT_LT(worst, tolerance * scale) << "largest gradient component " << scale;
}

} // namespace dp::test

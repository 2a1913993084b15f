// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DeterministicRandom.h
 * @brief Random numbers that are the same on every platform for the same seed and stream:
 *        std::mt19937_64's sequence is fixed by the C++ standard, and the conversions to
 *        uniform and Gaussian numbers here are our own (the standard distributions are
 *        implementation-defined). The samplers draw one stream per frame (and camera), so a
 *        frame's numbers never depend on which frames were made before.
 */
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

namespace dp
{

class DeterministicRandom
{
public:
  DeterministicRandom(std::uint64_t seed, std::uint64_t stream)
      : Engine(mix(seed ^ mix(stream + 0x9E3779B97F4A7C15ULL)))
  {
  }
  /** In [0, 1). */
  double uniform() { return static_cast<double>(Engine() >> 11) * 0x1.0p-53; }
  /** Standard normal (Box-Muller; 1 - u keeps the logarithm's argument in (0, 1]). */
  double gaussian()
  {
    const double u = 1.0 - uniform(), v = uniform();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(6.283185307179586 * v);
  }
  /** SplitMix64's finaliser: spreads a seed's bits. */
  static std::uint64_t mix(std::uint64_t x)
  {
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
    return x ^ (x >> 31);
  }

private:
  std::mt19937_64 Engine;
};

} // namespace dp

// SPDX-License-Identifier: BSD-3-Clause
// Loops over vertices or points on all threads (TBB), in fixed blocks: the body must touch only
// the entries of its own index, so results are the same for any thread count.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>

namespace dp
{

/** body(i) for every i in [0, count), on all threads in blocks of 128. */
template <typename Body>
void forEachIndex(std::size_t count, const Body& body)
{
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 128),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      for (std::size_t i = range.begin(); i != range.end(); ++i)
                        body(i);
                    });
}

} // namespace dp

// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/RecoveryPolicy.h"

#include <algorithm>
#include <cmath>

namespace dp
{

namespace
{
// The take's usual share: the median of the last frames kept.
double usual(const std::vector<FrameQuality>& recent, double FrameQuality::*share)
{
  std::vector<double> shares;
  for (const FrameQuality& q : recent)
    shares.push_back(q.*share);
  if (shares.empty())
    return 0.0;
  std::nth_element(shares.begin(), shares.begin() + static_cast<std::ptrdiff_t>(shares.size() / 2),
                   shares.end());
  return shares[shares.size() / 2];
}
} // namespace

bool RecoveryPolicy::beyondUsual(const FrameQuality& q, double FrameQuality::*share) const
{
  // The margin: the option's, or three standard errors of the usual share among the points
  // judged, whichever is larger (a share measured on fewer points varies more by chance).
  const double u = usual(Recent, share);
  const double n = static_cast<double>(q.samples);
  const double chance = q.samples > 0 ? 3 * std::sqrt(u * (1 - u) / n) : 0.0;
  return q.*share > u + std::max(Options.margin, chance);
}

bool RecoveryPolicy::torn(const FrameQuality& q) const
{
  return Options.stiffRetry && q.tear > Options.tearGrowth;
}

bool RecoveryPolicy::doubtful(const FrameQuality& q) const
{
  // More mesh without data than usual may be a limb left behind (its data explained by a
  // neighbour's mesh) as well as a hole: measured, retries there find such limbs again.
  if (Recent.empty())
    return false;
  return beyondUsual(q, &FrameQuality::unexplained) || beyondUsual(q, &FrameQuality::unsupported) ||
         torn(q);
}

bool RecoveryPolicy::failed(const FrameQuality& q) const
{
  // Mesh without data is no failure by itself: a hole in the data (a scanner's, moving from frame
  // to frame) looks the same, but there the solve started over the same missing data. A limb
  // caught by another's data tears a strip that covers almost nothing: the edges' growth sees it.
  if (Recent.empty())
    return false;
  return beyondUsual(q, &FrameQuality::unexplained) || beyondUsual(q, &FrameQuality::departed) ||
         torn(q);
}

bool RecoveryPolicy::prefers(const FrameQuality& retry, const FrameQuality& best,
                             bool tornAtFirst) const
{
  // The scores of two plausible fits differ by noise, and a start from elsewhere breaks the
  // motion's continuity: another start must do clearly better.
  const bool better = score(retry) < Options.retryShare * score(best) &&
                      score(retry) < score(best) - 0.5 * Options.margin;
  const bool mends = tornAtFirst && torn(best) && !torn(retry) &&
                     score(retry) < score(best) + 0.5 * Options.margin;
  return better || mends;
}

void RecoveryPolicy::frameKept(const FrameQuality& kept)
{
  InDoubt = Options.enabled && doubtful(kept);
  InDoubtInARow = InDoubt ? InDoubtInARow + 1 : 0;
  // Only frames that fit set the usual: a run of frames in doubt (a limb lost for many frames)
  // never becomes what the take usually is, so each of its frames stays retried and flagged.
  if (!InDoubt)
    Recent.push_back(kept);
  if (Recent.size() > Options.window)
    Recent.erase(Recent.begin());
}

bool RecoveryPolicy::referencesFollow() const
{
  return !InDoubt || InDoubtInARow >= Options.persistentFailures;
}

void RecoveryPolicy::reset()
{
  Recent.clear();
  InDoubtInARow = 0;
}

} // namespace dp

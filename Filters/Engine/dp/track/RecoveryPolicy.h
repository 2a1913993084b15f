// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file RecoveryPolicy.h
 * @brief When a tracked frame is in doubt, when it is flagged, and which retry to keep
 *        (RecoveryOptions), judged against the take's usual quality.
 *
 * Beyond the paper (which has no failure detection). A frame's quality (FrameQuality) is compared
 * with what is usual in the take: the median of each share over the last `window` frames kept.
 * A frame is *in doubt* (worth other starts) when any share exceeds the usual by more than
 * the margin (`margin`, or three standard errors of the usual share among the points judged,
 * whichever is larger), or a limb tore (a stiff edge grew beyond `tearGrowth` mean edge lengths);
 * it is *failed* (flagged) only for unexplained data, departed mesh or a tear: mesh without data
 * looks just like a hole in the data. The first frame sets what is usual and is never in doubt.
 * A frame in doubt never sets the usual, however many follow it: a limb lost for a hundred
 * frames is flagged and retried in each. After `persistentFailures` frames in doubt in a row the
 * coarse level's reference follows the take (referencesFollow), so that tracking goes on.
 *
 * Limits: the usual is a median of a few frames, so a take that starts badly has a lax baseline
 * until it improves; data the template lacks (a prop brought in) stay unexplained, and flagged,
 * for as long as they stay.
 */
#pragma once

#include "dp/track/FrameQuality.h"
#include "dp/track/TrackerOptions.h"

#include <vector>

namespace dp
{

class RecoveryPolicy
{
public:
  explicit RecoveryPolicy(const RecoveryOptions& options) : Options(options) {}

  /** A limb tore (only when stiff retries are on: a tear is then a failure and retried). */
  bool torn(const FrameQuality& q) const;
  /** Worth other starts: any share beyond the usual, or a tear. */
  bool doubtful(const FrameQuality& q) const;
  /** Flagged: unexplained data or departed mesh beyond the usual, or a tear. */
  bool failed(const FrameQuality& q) const;
  /** Whether a retry's result replaces the best so far (`tornAtFirst`: the first attempt tore):
   *  clearly better (below `retryShare` of the best's score and half a margin under it), or it
   *  mends a tear and explains the data about as well. */
  bool prefers(const FrameQuality& retry, const FrameQuality& best, bool tornAtFirst) const;

  /** A frame begins; a frame without data is in doubt; a frame was kept with this quality. */
  void frameBegins() { InDoubt = false; }
  void frameWithoutData() { InDoubt = true; }
  void frameKept(const FrameQuality& kept);

  /** The last frame stayed in doubt after its retries. */
  bool inDoubt() const { return InDoubt; }
  /** The last frame may move the take's references (not in doubt, or doubt persists). */
  bool referencesFollow() const;
  /** Forget the take: the next frame is a first frame again. */
  void reset();

  /** What a frame is scored by among its attempts: its shares of data and mesh unmatched. */
  static double score(const FrameQuality& q) { return q.unexplained + q.unsupported; }

private:
  bool beyondUsual(const FrameQuality& q, double FrameQuality::*share) const;

  RecoveryOptions Options;
  std::vector<FrameQuality> Recent; // the last frames kept that set the baseline
  bool InDoubt = false;
  int InDoubtInARow = 0;
};

} // namespace dp

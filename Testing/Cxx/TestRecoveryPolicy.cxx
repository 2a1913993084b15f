// SPDX-License-Identifier: BSD-3-Clause
// RecoveryPolicy: the take's usual quality, doubt against failure, which retry is kept, and the
// baseline following a take that has changed.
#include "dp/track/RecoveryPolicy.h"

#include <gtest/gtest.h>

namespace
{

dp::FrameQuality quality(double unexplained, double unsupported = 0, double departed = 0,
                         double tear = 0)
{
  return {unexplained, unsupported, departed, tear};
}

TEST(RecoveryPolicy, TheFirstFrameSetsTheUsualAndIsNeverInDoubt)
{
  dp::RecoveryPolicy policy(dp::RecoveryOptions{});
  EXPECT_FALSE(policy.doubtful(quality(0.5, 0.5, 0.5, 10)));
  EXPECT_FALSE(policy.failed(quality(0.5, 0.5, 0.5, 10)));
  policy.frameKept(quality(0.02)); // sparse data the template lacks: usual from now on
  EXPECT_FALSE(policy.inDoubt());
  EXPECT_FALSE(policy.doubtful(quality(0.022)));
  EXPECT_TRUE(policy.doubtful(quality(0.03))); // beyond the usual by more than the margin
  EXPECT_TRUE(policy.failed(quality(0.03)));
}

TEST(RecoveryPolicy, MeshWithoutDataIsRetriedButNotFlagged)
{
  dp::RecoveryPolicy policy(dp::RecoveryOptions{});
  policy.frameKept(quality(0, 0));
  const dp::FrameQuality hole = quality(0, 0.05);
  EXPECT_TRUE(policy.doubtful(hole)); // a limb left behind looks so: worth other starts
  EXPECT_FALSE(policy.failed(hole));  // a hole in the data looks so too: no flag
  const dp::FrameQuality departed = quality(0, 0.05, 0.05);
  EXPECT_TRUE(policy.failed(departed));
  EXPECT_TRUE(policy.failed(quality(0, 0, 0, 2.5))); // torn
  dp::RecoveryOptions noStiff;
  noStiff.stiffRetry = false;
  dp::RecoveryPolicy lax(noStiff);
  lax.frameKept(quality(0, 0));
  EXPECT_FALSE(lax.failed(quality(0, 0, 0, 2.5)));
}

TEST(RecoveryPolicy, ARetryIsKeptOnlyWhenClearlyBetterOrItMendsATear)
{
  dp::RecoveryPolicy policy(dp::RecoveryOptions{});
  const dp::FrameQuality best = quality(0.05, 0.05); // score 0.1
  EXPECT_TRUE(policy.prefers(quality(0.03, 0.03), best, false));
  EXPECT_FALSE(policy.prefers(quality(0.04, 0.04), best, false)); // 0.8 of it: noise
  // Tiny scores: the share alone is not enough, half a margin must be gained too.
  EXPECT_FALSE(policy.prefers(quality(0.0005), quality(0.001), false));
  const dp::FrameQuality torn = quality(0.05, 0.05, 0, 3);
  EXPECT_TRUE(policy.prefers(quality(0.05, 0.051), torn, true)); // mends, about as good
  EXPECT_FALSE(policy.prefers(quality(0.05, 0.051), torn, false));
  EXPECT_FALSE(policy.prefers(quality(0.06, 0.06), torn, true)); // mends but explains less
}

// A run of frames in doubt (a limb lost for many frames) never becomes the usual: each stays
// flagged however long it lasts; the coarse level's reference follows after a few, so that
// tracking goes on.
TEST(RecoveryPolicy, PersistentFailuresStayFlaggedWhileTheReferencesFollow)
{
  dp::RecoveryOptions options;
  options.persistentFailures = 3;
  dp::RecoveryPolicy policy(options);
  policy.frameKept(quality(0));
  const dp::FrameQuality lost = quality(0.1); // a forearm's points unexplained
  for (int f = 1; f <= 100; ++f)
  {
    EXPECT_TRUE(policy.failed(lost)) << "frame " << f;
    policy.frameKept(lost);
    EXPECT_TRUE(policy.inDoubt());
    EXPECT_EQ(policy.referencesFollow(), f >= 3) << "frame " << f;
  }
  policy.frameKept(quality(0.001)); // found again: the usual is still the good frames'
  EXPECT_FALSE(policy.inDoubt());
  EXPECT_TRUE(policy.failed(lost));
  policy.reset();
  EXPECT_FALSE(policy.doubtful(quality(0.5))); // a first frame again
}

// The margin follows the chance in a share measured on few points: 3 % unexplained among 100
// points is within three standard errors of a usual 2 %, among 100 000 it is not.
TEST(RecoveryPolicy, TheMarginFollowsTheChanceInAShareOfFewPoints)
{
  dp::RecoveryPolicy policy(dp::RecoveryOptions{});
  policy.frameKept(quality(0.02));
  dp::FrameQuality few = quality(0.03), many = quality(0.03);
  few.samples = 100;
  many.samples = 100000;
  EXPECT_FALSE(policy.failed(few));
  EXPECT_TRUE(policy.failed(many));
}

TEST(RecoveryPolicy, RecoveryOffNeverDoubts)
{
  dp::RecoveryOptions off;
  off.enabled = false;
  dp::RecoveryPolicy policy(off);
  policy.frameKept(quality(0));
  policy.frameKept(quality(0.5));
  EXPECT_FALSE(policy.inDoubt());
}

} // namespace

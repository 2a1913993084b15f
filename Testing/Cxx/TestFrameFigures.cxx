// SPDX-License-Identifier: BSD-3-Clause
// FrameFigures: one tracked frame's figures, declared once. Every member is in the table once,
// under a name of its own; the figures of a frame are its result's, with the frame's own time
// and the retries' share worked out; report.json's keys and the Markdown table follow the names.
#include "dp/track/FrameFigures.h"
#include "dp/track/Tracker.h"

#include <gtest/gtest.h>

#include <cctype>
#include <set>
#include <string>

namespace
{

TEST(FrameFigures, EveryMemberIsListedOnceUnderANameOfItsOwn)
{
  // Every member is a double: as many fields as doubles in the record means none is left out
  // when each field holds another member (a value written through each is read back through it).
  const auto& fields = dp::FrameFigures::fields();
  EXPECT_EQ(fields.size() * sizeof(double), sizeof(dp::FrameFigures));
  dp::FrameFigures figures;
  for (std::size_t i = 0; i < fields.size(); ++i)
    figures.*fields[i].value = static_cast<double>(i + 1);
  std::set<std::string> names;
  for (std::size_t i = 0; i < fields.size(); ++i)
  {
    const auto& f = fields[i];
    EXPECT_EQ(figures.*f.value, static_cast<double>(i + 1)) << "a member listed twice: " << f.name;
    EXPECT_TRUE(names.insert(f.name).second) << "twice: " << f.name;
    EXPECT_TRUE(std::isupper(static_cast<unsigned char>(f.name[0]))) << f.name;
    EXPECT_GT(std::string(f.doc).size(), 5u) << f.name;
  }
  // The stages: the six times from the data's preparation to the retries, in the table's order.
  const auto& stages = dp::FrameFigures::stages();
  ASSERT_EQ(stages.size(), 6u);
  const char* expected[] = {"DataSeconds", "PredictionSeconds", "CoarseSeconds",
                            "FineSeconds", "QualitySeconds",    "RetrySeconds"};
  for (std::size_t i = 0; i < 6; ++i)
    EXPECT_EQ(std::string(stages[i].name), expected[i]);
}

TEST(FrameFigures, AFramesFiguresAreItsResultsWithItsOwnTime)
{
  dp::FrameResult r;
  r.pointsGiven = 12345;
  r.iterations = 7;
  r.coarseIterations = 3;
  r.internalEnergy = 0.25;
  r.distanceEnergy = 1.5;
  r.seconds = 10;
  r.overlapped = 2;
  r.timings = {1.0, 0.5, 2.0, 3.0, 0.25};
  r.unexplained = 0.125;
  r.unsupported = 0.375;
  r.tear = 1.75;
  r.noise = 0.003;
  r.retries = 1;
  r.failed = true;
  const dp::FrameFigures f = dp::FrameFigures::of(r, 42, 0.06);
  EXPECT_EQ(f.frameIndex, 42);
  EXPECT_EQ(f.points, 12345);
  EXPECT_EQ(f.iterations, 7);
  EXPECT_EQ(f.coarseIterations, 3);
  EXPECT_EQ(f.internalEnergy, 0.25);
  EXPECT_EQ(f.distanceEnergy, 1.5);
  EXPECT_EQ(f.seconds, 8); // less what ran beside the frame before
  EXPECT_EQ(f.overlappedSeconds, 2);
  EXPECT_EQ(f.dataSeconds, 1.0);
  EXPECT_EQ(f.predictionSeconds, 0.5);
  EXPECT_EQ(f.coarseSeconds, 2.0);
  EXPECT_EQ(f.fineSeconds, 3.0);
  EXPECT_EQ(f.qualitySeconds, 0.25);
  EXPECT_EQ(f.retrySeconds, 10 - 6.75); // the frame's work the kept attempt's stages leave
  EXPECT_EQ(f.emptyFrame, 0);
  EXPECT_EQ(f.unexplained, 0.125);
  EXPECT_EQ(f.unsupported, 0.375);
  EXPECT_EQ(f.largestStretch, 1.75);
  EXPECT_EQ(f.retries, 1);
  EXPECT_EQ(f.failed, 1);
  EXPECT_EQ(f.dataReach, 0.06);
  EXPECT_EQ(f.dataNoise, 0.003);
  EXPECT_EQ(f.seen, 1 - 0.375);

  // No retries: no retry time, whatever is left over; an empty frame sees nothing.
  r.retries = 0;
  r.failed = false;
  r.emptyFrame = true;
  const dp::FrameFigures g = dp::FrameFigures::of(r, 0, 0.06);
  EXPECT_EQ(g.retrySeconds, 0);
  EXPECT_EQ(g.failed, 0);
  EXPECT_EQ(g.emptyFrame, 1);
  EXPECT_EQ(g.seen, 0);
  // Stages that took longer than the frame (clock skew): no negative retry time.
  r.retries = 2;
  r.seconds = 1;
  EXPECT_EQ(dp::FrameFigures::of(r, 0, 0.06).retrySeconds, 0);
}

TEST(FrameFigures, ReportKeysAndTheMarkdownTableFollowTheNames)
{
  EXPECT_EQ(dp::FrameFigures::reportKey("LargestStretch"), "largestStretch");
  EXPECT_EQ(dp::FrameFigures::reportKey("Seen"), "seen");
  EXPECT_EQ(dp::FrameFigures::reportKey(""), "");
  const std::string md = dp::FrameFigures::markdown();
  EXPECT_EQ(md.rfind("| field data | report.json | what |\n|---|---|---|\n", 0), 0u);
  std::size_t rows = 0;
  for (char c : md)
    rows += c == '\n';
  EXPECT_EQ(rows, 2 + dp::FrameFigures::fields().size());
  for (const auto& f : dp::FrameFigures::fields())
  {
    const std::string row = std::string("| `") + f.name + "` | `" +
                            dp::FrameFigures::reportKey(f.name) + "` | " + f.doc + " |\n";
    EXPECT_NE(md.find(row), std::string::npos) << f.name;
  }
}

} // namespace

// SPDX-License-Identifier: BSD-3-Clause
// Listing a sequence: natural order, glob patterns, .series files, times, and their errors.
#include "TestUtilities.h"

#include "dp/io/FrameSequence.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace
{

using dp::test::expectFileError;
using dp::test::TempDir;
using dp::test::writeText;

std::string name(const std::string& path)
{
  return std::filesystem::path(path).filename().string();
}

TEST(NaturalOrder, NumbersCompareByValue)
{
  EXPECT_TRUE(dp::naturalLess("2.ply", "10.ply"));
  EXPECT_FALSE(dp::naturalLess("10.ply", "2.ply"));
  EXPECT_TRUE(dp::naturalLess("frame9", "frame10"));
  EXPECT_TRUE(dp::naturalLess("a1b2", "a1b10"));
  EXPECT_TRUE(dp::naturalLess("f_007", "f_08"));
  EXPECT_TRUE(dp::naturalLess("f1", "f01")); // equal value: fewer leading zeros first
  EXPECT_TRUE(dp::naturalLess("abc", "abd"));
  EXPECT_TRUE(dp::naturalLess("abc", "abcd"));
  EXPECT_FALSE(dp::naturalLess("abc", "abc"));
}

TEST(Glob, StarsQuestionMarksAndClasses)
{
  EXPECT_TRUE(dp::globMatch("*", "anything.ply"));
  EXPECT_TRUE(dp::globMatch("frame_*.ply", "frame_0001.ply"));
  EXPECT_FALSE(dp::globMatch("frame_*.ply", "frame_0001.pcd"));
  EXPECT_TRUE(dp::globMatch("f??.xyz", "f12.xyz"));
  EXPECT_FALSE(dp::globMatch("f??.xyz", "f1.xyz"));
  EXPECT_TRUE(dp::globMatch("scan[0-9].*", "scan7.pcd"));
  EXPECT_FALSE(dp::globMatch("scan[!0-9].*", "scan7.pcd"));
  EXPECT_TRUE(dp::globMatch("*a*b*c", "xxaxxbxxc"));
  EXPECT_FALSE(dp::globMatch("*a*b*c", "xxaxxcxxb"));
}

TEST(FrameSequence, DirectoryIsFilteredByPatternAndExtensionAndSortedNaturally)
{
  TempDir dir;
  for (const char* f : {"f10.ply", "f2.ply", "f1.ply", "notes.md", "g3.ply", "points.series"})
    writeText(dir.file(f), "");
  std::filesystem::create_directory(dir.file("sub.ply"));
  const auto all = dp::FrameSequence::fromDirectory(dir.path(), "*", 0.5);
  ASSERT_EQ(all.size(), 4u);
  EXPECT_EQ(name(all[0].path), "f1.ply");
  EXPECT_EQ(name(all[1].path), "f2.ply");
  EXPECT_EQ(name(all[2].path), "f10.ply");
  EXPECT_EQ(name(all[3].path), "g3.ply");
  EXPECT_DOUBLE_EQ(all[3].time, 1.5);
  const auto f = dp::FrameSequence::fromDirectory(dir.path(), "f*.ply");
  EXPECT_EQ(f.size(), 3u);
}

TEST(FrameSequence, DirectoryErrors)
{
  TempDir dir;
  expectFileError([&] { dp::FrameSequence::fromDirectory(dir.file("missing")); },
                  dir.file("missing"), "does not exist");
  expectFileError([&] { dp::FrameSequence::fromDirectory(dir.path()); }, dir.path(),
                  "no point files match");
  writeText(dir.file("a.ply"), "");
  expectFileError([&] { dp::FrameSequence::fromDirectory(dir.file("a.ply")); }, dir.file("a.ply"),
                  "is not a folder");
}

TEST(FrameSequence, SeriesFileGivesTimesAndResolvesRelativeNames)
{
  TempDir dir;
  const std::string series = dir.file("s.series");
  writeText(series, R"({"file-series-version":"1.0","files":[
    {"name":"b.ply","time":0.5},{"name":"a.ply","time":0.25},{"name":"/abs/c.ply","time":2}]})");
  const auto s = dp::FrameSequence::fromSeriesFile(series);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].path, dir.file("a.ply")); // sorted by time
  EXPECT_DOUBLE_EQ(s[0].time, 0.25);
  EXPECT_EQ(s[2].path, "/abs/c.ply");
  EXPECT_EQ(s.frameAtTime(0.0), 0u);
  EXPECT_EQ(s.frameAtTime(0.5), 1u);
  EXPECT_EQ(s.frameAtTime(0.4999999999999), 1u);
  EXPECT_EQ(s.frameAtTime(1.9), 1u);
  EXPECT_EQ(s.frameAtTime(100), 2u);
}

TEST(FrameSequence, BadSeriesFilesAreErrorsNamingTheFile)
{
  TempDir dir;
  const std::string series = dir.file("bad.series");
  const std::pair<std::string, std::string> cases[] = {
      {"{not json", "not valid JSON"},
      {R"({"file-series-version":"1.0"})", "\"files\" array"},
      {R"({"files":[]})", "lists no files"},
      {R"({"files":[{"time":1}]})", "has no \"name\""},
      {R"({"files":[{"name":"a.ply","time":"soon"}]})", "non-numeric"},
      {R"({"files":[{"name":"a.ply","time":1},{"name":"b.ply","time":1}]})", "share the time"},
  };
  for (const auto& [text, expected] : cases)
  {
    writeText(series, text);
    expectFileError([&] { dp::FrameSequence::fromSeriesFile(series); }, series, expected);
  }
  expectFileError([&] { dp::FrameSequence::fromSeriesFile(dir.file("none.series")); },
                  dir.file("none.series"), "cannot open");
}

TEST(FrameSequence, ExplicitListKeepsOrderAndRejectsBadInterval)
{
  const auto s = dp::FrameSequence::fromFiles({"z.ply", "a.ply"}, 2.0);
  EXPECT_EQ(s[0].path, "z.ply");
  EXPECT_DOUBLE_EQ(s[1].time, 2.0);
  EXPECT_THROW(dp::FrameSequence::fromFiles({"a.ply"}, 0.0), std::invalid_argument);
  EXPECT_THROW(dp::FrameSequence::fromFiles({"a.ply"}, -1.0), std::invalid_argument);
}

} // namespace

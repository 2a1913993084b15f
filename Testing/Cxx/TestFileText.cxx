// SPDX-License-Identifier: BSD-3-Clause
// FileText: whole files read back byte for byte as written, every failure a FileError naming the
// file, writes that leave neither a half file nor a stray one; and the text scanning the format
// parsers share (lines, tokens, numbers, counts).
#include "TestUtilities.h"

#include "dp/io/FileText.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace
{

using dp::test::expectFileError;
using dp::test::TempDir;

// Every byte value, with line ends of both kinds and a zero byte inside.
std::string everyByte()
{
  std::string bytes = "first line\r\nsecond\n";
  for (int b = 0; b < 256; ++b)
    bytes += static_cast<char>(b);
  bytes += std::string(100000, 'x'); // more than one read buffer
  return bytes + '\0';
}

TEST(FileText, ReadsBackEveryByteItWrote)
{
  TempDir dir;
  const std::string path = dir.file("bytes.bin");
  const std::string bytes = everyByte();
  dp::support::writeWholeFile(path, bytes);
  EXPECT_EQ(dp::test::readText(path), bytes); // what is on disk, read independently
  EXPECT_EQ(dp::support::readWholeFile(path), bytes);
  dp::support::writeWholeFile(path, "");
  EXPECT_EQ(dp::support::readWholeFile(path), "");
}

TEST(FileText, AFileThatCannotBeReadOrWrittenIsNamed)
{
  TempDir dir;
  const std::string missing = dir.file("missing.ply");
  expectFileError([&] { dp::support::readWholeFile(missing); }, missing, "cannot open file");
  expectFileError([&] { dp::support::readWholeFile(dir.path()); }, dir.path(), "is a folder");
  const std::string nowhere = dir.file("no/such/folder/out.ply");
  expectFileError([&] { dp::support::writeWholeFile(nowhere, "x"); }, nowhere,
                  "cannot create file");
  EXPECT_FALSE(std::filesystem::exists(nowhere));
}

TEST(FileText, AWriteIsPutInPlaceWholeOrNotAtAll)
{
  TempDir dir;
  const std::string path = dir.file("out.dpz");
  // A write that succeeds: the file under its name, nothing beside it.
  dp::support::writeBesideAndMove(path, [](const std::string& partial)
                                  { dp::support::writeWholeFile(partial, "whole"); });
  EXPECT_EQ(dp::support::readWholeFile(path), "whole");
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
  // A write that fails half way: its exception passes, the old file stays, no partial is left.
  EXPECT_THROW(dp::support::writeBesideAndMove(path,
                                               [](const std::string& partial)
                                               {
                                                 dp::support::writeWholeFile(partial, "half");
                                                 throw std::runtime_error("disk full");
                                               }),
               std::runtime_error);
  EXPECT_EQ(dp::support::readWholeFile(path), "whole");
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
  // A name that cannot take the file (a folder with something in it): refused by that name, and
  // the written file beside it removed.
  const std::string folder = dir.file("taken");
  std::filesystem::create_directories(folder + "/inside");
  expectFileError(
      [&]
      {
        dp::support::writeBesideAndMove(folder, [](const std::string& partial)
                                        { dp::support::writeWholeFile(partial, "bytes"); });
      },
      folder, "cannot put the written file in place");
  EXPECT_FALSE(std::filesystem::exists(folder + ".partial"));
  EXPECT_TRUE(std::filesystem::is_directory(folder + "/inside"));
}

TEST(FileText, LinesEndAtEitherLineEndAndTheLastNeedsNone)
{
  std::string_view text = "ply\r\nformat ascii 1.0\n\nlast";
  std::vector<std::string> lines;
  std::string_view line;
  while (dp::support::nextLine(text, line))
    lines.emplace_back(line);
  EXPECT_EQ(lines, (std::vector<std::string>{"ply", "format ascii 1.0", "", "last"}));
  EXPECT_TRUE(text.empty());
  std::string_view ending = "one\n";
  ASSERT_TRUE(dp::support::nextLine(ending, line));
  EXPECT_EQ(line, "one");
  EXPECT_FALSE(dp::support::nextLine(ending, line)); // no empty line after the last "\n"
}

TEST(FileText, TokensAreSplitAtWhitespaceAndCommasWhenAsked)
{
  std::string_view s = " \t1.5,2\v\f-3 ,, x\r\n";
  std::vector<std::string> plain, commas;
  std::string_view copy = s;
  for (std::string_view t = dp::support::nextToken(copy); !t.empty();
       t = dp::support::nextToken(copy))
    plain.emplace_back(t);
  copy = s;
  for (std::string_view t = dp::support::nextToken(copy, true); !t.empty();
       t = dp::support::nextToken(copy, true))
    commas.emplace_back(t);
  EXPECT_EQ(plain, (std::vector<std::string>{"1.5,2", "-3", ",,", "x"}));
  EXPECT_EQ(commas, (std::vector<std::string>{"1.5", "2", "-3", "x"}));
  EXPECT_EQ(dp::support::toLower("Vertex_INDICES 42"), "vertex_indices 42");
}

TEST(FileText, NumbersAreWholeTokensAndCountsWholeNumbersInRange)
{
  double v = 0;
  EXPECT_TRUE(dp::support::parseNumber("+1.5", v));
  EXPECT_EQ(v, 1.5);
  EXPECT_TRUE(dp::support::parseNumber("-2e3", v));
  EXPECT_EQ(v, -2000);
  EXPECT_TRUE(dp::support::parseNumber("nan", v));
  EXPECT_TRUE(std::isnan(v));
  EXPECT_TRUE(dp::support::parseNumber("-inf", v));
  EXPECT_EQ(v, -HUGE_VAL);
  for (const char* bad : {"", "+", "1.5x", " 1", "1 ", "0x", "one", "++1"})
    EXPECT_FALSE(dp::support::parseNumber(bad, v)) << "'" << bad << "'";

  EXPECT_EQ(dp::support::LargestCount, std::ldexp(1.0, 50));
  const double limit = dp::support::LargestCount;
  EXPECT_TRUE(dp::support::wholeNumberWithin(0, limit));
  EXPECT_TRUE(dp::support::wholeNumberWithin(limit, limit));
  EXPECT_TRUE(dp::support::wholeNumberWithin(-limit, limit));
  EXPECT_FALSE(dp::support::wholeNumberWithin(2 * limit, limit));
  EXPECT_FALSE(dp::support::wholeNumberWithin(2.5, limit));
  EXPECT_FALSE(dp::support::wholeNumberWithin(std::nan(""), limit));
  EXPECT_FALSE(dp::support::wholeNumberWithin(HUGE_VAL, limit));
}

} // namespace

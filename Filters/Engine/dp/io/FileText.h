// SPDX-License-Identifier: BSD-3-Clause
// Internal helpers shared by the format parsers: whole-file reading and number scanning.
#pragma once

#include "dp/io/PointCloud.h"

#include <charconv>
#include <cmath>
#include <functional>
#include <string>
#include <string_view>

namespace dp::support
{

/** Reads a whole file; throws FileError naming it when it is missing or unreadable. */
std::string readWholeFile(const std::string& path);

/** Writes a whole file; throws FileError naming it on failure. */
void writeWholeFile(const std::string& path, const std::string& bytes);

/** Renames `partial`, written beside `path`, onto `path`. On failure removes `partial` and
 *  throws FileError naming `path`: writers write beside and rename, so a failure leaves neither
 *  a half file under the name nor a stray one beside it. */
void moveIntoPlace(const std::string& partial, const std::string& path);

/** Writes `path` the same way: `write` writes the file it is given (`path` + ".partial"); if it
 *  throws, that file is removed and the exception passed on, else it is moved into place. */
void writeBesideAndMove(const std::string& path,
                        const std::function<void(const std::string& partial)>& write);

std::string toLower(std::string_view s);

/** Splits off the next line (without its "\n" or "\r\n"); false at the end of text. */
inline bool nextLine(std::string_view& text, std::string_view& line)
{
  if (text.empty())
  {
    return false;
  }
  const std::size_t eol = text.find('\n');
  line = text.substr(0, eol);
  text = eol == std::string_view::npos ? std::string_view{} : text.substr(eol + 1);
  if (!line.empty() && line.back() == '\r')
  {
    line.remove_suffix(1);
  }
  return true;
}

/** Skips separators (whitespace, and commas when commaIsSeparator). */
inline void skipSeparators(std::string_view& s, bool commaIsSeparator = false)
{
  std::size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\n' || s[i] == '\r' ||
                          s[i] == '\f' || s[i] == '\v' || (commaIsSeparator && s[i] == ',')))
  {
    ++i;
  }
  s.remove_prefix(i);
}

/** Returns the next separator-delimited token (empty at the end). */
inline std::string_view nextToken(std::string_view& s, bool commaIsSeparator = false)
{
  skipSeparators(s, commaIsSeparator);
  std::size_t i = 0;
  while (i < s.size() && !(s[i] == ' ' || s[i] == '\t' || s[i] == '\n' || s[i] == '\r' ||
                           s[i] == '\f' || s[i] == '\v' || (commaIsSeparator && s[i] == ',')))
  {
    ++i;
  }
  std::string_view token = s.substr(0, i);
  s.remove_prefix(i);
  return token;
}

/** The largest element or point count a header may declare: 2^50, a petabyte of points. */
constexpr double LargestCount = 1125899906842624.0;

/** True for a whole number from -limit to limit: what may be cast to an integer type (casting
 *  a NaN, an infinity or anything out of range is undefined behaviour). */
inline bool wholeNumberWithin(double value, double limit)
{
  return value >= -limit && value <= limit && std::floor(value) == value; // false for NaN
}

/** Parses a whole token as a number (accepts nan/inf); false if it is not one. */
inline bool parseNumber(std::string_view token, double& value)
{
  if (!token.empty() && token.front() == '+')
  {
    token.remove_prefix(1);
  }
  if (token.empty())
  {
    return false;
  }
  const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
  return result.ec == std::errc() && result.ptr == token.data() + token.size();
}

} // namespace dp::support

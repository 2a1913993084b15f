// SPDX-License-Identifier: BSD-3-Clause
#include "dp/io/FrameSequence.h"

#include "dp/io/FileText.h"
#include "dp/io/PointCloud.h"
#include "dp/io/PointCloudIO.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace fs = std::filesystem;

namespace dp
{

bool naturalLess(const std::string& a, const std::string& b)
{
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size())
  {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i]));
    const bool db = std::isdigit(static_cast<unsigned char>(b[j]));
    if (da && db)
    {
      // Compare digit runs by value: skip leading zeros, then longer run is larger.
      std::size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie])))
        ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je])))
        ++je;
      std::size_t is = i, js = j;
      while (is + 1 < ie && a[is] == '0')
        ++is;
      while (js + 1 < je && b[js] == '0')
        ++js;
      if (ie - is != je - js)
        return ie - is < je - js;
      const int c = a.compare(is, ie - is, b, js, je - js);
      if (c != 0)
        return c < 0;
      if (ie - i != je - j) // same value: fewer leading zeros first
        return ie - i < je - j;
      i = ie;
      j = je;
    }
    else
    {
      if (a[i] != b[j])
        return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

namespace
{
// Whether c is in the character class ([abc], [a-z], [!a-z] or [^a-z]) that starts at
// pattern[p] == '['; advances p past the class.
bool classMatches(const std::string& pattern, std::size_t& p, char c)
{
  std::size_t q = p + 1;
  bool negate = q < pattern.size() && (pattern[q] == '!' || pattern[q] == '^');
  if (negate)
    ++q;
  bool matched = false;
  bool first = true;
  while (q < pattern.size() && (first || pattern[q] != ']'))
  {
    first = false;
    if (q + 2 < pattern.size() && pattern[q + 1] == '-' && pattern[q + 2] != ']')
    {
      matched = matched || (c >= pattern[q] && c <= pattern[q + 2]);
      q += 3;
    }
    else
    {
      matched = matched || c == pattern[q];
      ++q;
    }
  }
  p = q + 1;
  return matched != negate;
}
} // namespace

bool globMatch(const std::string& pattern, const std::string& name)
{
  // Iterative matcher with single-star backtracking; O(|pattern| * |name|) worst case.
  std::size_t p = 0, n = 0, starP = std::string::npos, starN = 0;
  while (n < name.size())
  {
    if (p < pattern.size() && pattern[p] == '*')
    {
      starP = p++;
      starN = n;
      continue;
    }
    if (p < pattern.size() && pattern[p] == '[' && pattern.find(']', p + 2) != std::string::npos)
    {
      std::size_t next = p;
      if (classMatches(pattern, next, name[n]))
      {
        p = next;
        ++n;
        continue;
      }
    }
    else if (p < pattern.size() && (pattern[p] == '?' || pattern[p] == name[n]))
    {
      ++p;
      ++n;
      continue;
    }
    if (starP == std::string::npos)
      return false;
    p = starP + 1;
    n = ++starN;
  }
  while (p < pattern.size() && pattern[p] == '*')
    ++p;
  return p == pattern.size();
}

FrameSequence FrameSequence::fromDirectory(const std::string& directory, const std::string& pattern,
                                           double frameInterval)
{
  std::error_code ec;
  if (!fs::is_directory(directory, ec))
  {
    throw FileError(directory,
                    fs::exists(directory, ec) ? "is not a folder" : "folder does not exist");
  }
  std::vector<std::string> names;
  for (fs::directory_iterator it(directory, ec), end; !ec && it != end; it.increment(ec))
  {
    const std::string name = it->path().filename().string();
    if (!it->is_regular_file(ec) && !it->is_symlink(ec))
      continue;
    if (!globMatch(pattern.empty() ? "*" : pattern, name))
      continue;
    if (formatFromFileName(name) == PointFileFormat::Unknown)
      continue; // e.g. a README or the .series file itself next to the frames
    names.push_back(name);
  }
  if (ec)
  {
    throw FileError(directory, "cannot list folder (" + ec.message() + ")");
  }
  if (names.empty())
  {
    throw FileError(directory, "no point files match the pattern '" + pattern +
                                   "' (readable: " + readableExtensions() + ")");
  }
  std::sort(names.begin(), names.end(), naturalLess);
  std::vector<std::string> paths;
  for (const auto& name : names)
    paths.push_back((fs::path(directory) / name).string());
  return fromFiles(paths, frameInterval);
}

namespace
{

// A .series file read by its JSON events, keeping each entry's name and time alone: no document
// is built, so the file costs its frames and nothing more (about 4 bytes a byte of its text at
// worst), and nothing nests deeper than an entry's values. Depths: 1 the file's object, 2 its
// "files" array, 3 an entry, 4 an entry's values.
class SeriesEvents : public nlohmann::json_sax<nlohmann::json>
{
public:
  SeriesEvents(std::string path, fs::path base) : Path(std::move(path)), Base(std::move(base)) {}

  std::vector<Frame> frames() const
  {
    if (!FilesSeen)
      throw FileError(Path, "a .series file needs a \"files\" array "
                            "({\"file-series-version\":\"1.0\",\"files\":[...]})");
    return Frames;
  }

  bool start_object(std::size_t) override { return open(true); }
  bool start_array(std::size_t) override { return open(false); }
  bool end_object() override
  {
    if (Depth == 3 && InFiles)
      endEntry();
    --Depth;
    return true;
  }
  bool end_array() override
  {
    if (Depth == 2)
      InFiles = false;
    --Depth;
    return true;
  }
  bool key(string_t& k) override
  {
    if (Depth == 1)
      RootKey = k;
    else if (Depth == 3 && InFiles)
      EntryKey = k;
    return true;
  }
  bool null() override { return scalar(false, 0, nullptr); }
  bool boolean(bool) override { return scalar(false, 0, nullptr); }
  bool number_integer(number_integer_t v) override
  {
    return scalar(true, static_cast<double>(v), nullptr);
  }
  bool number_unsigned(number_unsigned_t v) override
  {
    return scalar(true, static_cast<double>(v), nullptr);
  }
  bool number_float(number_float_t v, const string_t&) override { return scalar(true, v, nullptr); }
  bool string(string_t& v) override { return scalar(false, 0, &v); }
  bool binary(binary_t&) override { return scalar(false, 0, nullptr); }
  bool parse_error(std::size_t, const std::string&, const nlohmann::json::exception& e) override
  {
    throw FileError(Path, std::string("not valid JSON: ") + e.what());
  }

private:
  bool open(bool object)
  {
    if (++Depth > 4)
      throw FileError(Path, "nested deeper than a .series file's entries");
    if (Depth == 1 && !object)
      throw FileError(Path, "a .series file needs a \"files\" array "
                            "({\"file-series-version\":\"1.0\",\"files\":[...]})");
    if (Depth == 2 && RootKey == "files")
    {
      FilesSeen = !object;
      InFiles = !object;
      Frames.clear();
    }
    else if (Depth == 3 && InFiles)
    {
      if (!object)
        noName();
      Entry = Frame{};
      Entry.time = static_cast<double>(Frames.size());
      Named = false;
    }
    else if (Depth == 4 && InFiles)
      scalar(false, 0, nullptr); // a list or an object as a name or a time
    return true;
  }

  // A value: a number, a string or something else (neither).
  bool scalar(bool number, double value, const string_t* text)
  {
    if (Depth == 1 && RootKey == "files")
      FilesSeen = InFiles = false, Frames.clear();
    else if (Depth == 2 && InFiles)
      noName();
    else if (Depth == 3 && InFiles && EntryKey == "name")
    {
      Named = text != nullptr;
      if (Named)
      {
        const fs::path name = *text;
        Entry.path = (name.is_absolute() ? name : Base / name).string();
      }
    }
    else if (Depth == 3 && InFiles && EntryKey == "time")
    {
      if (!number || !std::isfinite(value))
        throw FileError(Path,
                        "entry " + std::to_string(Frames.size()) + " has a non-numeric \"time\"");
      Entry.time = value;
    }
    return true;
  }

  void endEntry()
  {
    if (!Named)
      noName();
    Frames.push_back(Entry);
    EntryKey.clear();
  }

  [[noreturn]] void noName() const
  {
    throw FileError(Path,
                    "entry " + std::to_string(Frames.size()) + " of \"files\" has no \"name\"");
  }

  std::string Path;
  fs::path Base;
  std::vector<Frame> Frames;
  int Depth = 0;
  bool FilesSeen = false, InFiles = false, Named = false;
  std::string RootKey, EntryKey;
  Frame Entry;
};

} // namespace

FrameSequence FrameSequence::fromSeriesFile(const std::string& seriesPath)
{
  const std::string text = support::readWholeFile(seriesPath);
  SeriesEvents events(seriesPath, fs::path(seriesPath).parent_path());
  nlohmann::json::sax_parse(text, &events);
  FrameSequence sequence;
  sequence.Frames = events.frames();
  if (sequence.Frames.empty())
  {
    throw FileError(seriesPath, "the .series file lists no files");
  }
  // The pipeline needs increasing times: keep the file order, sorted by time.
  std::stable_sort(sequence.Frames.begin(), sequence.Frames.end(),
                   [](const Frame& a, const Frame& b) { return a.time < b.time; });
  for (std::size_t i = 1; i < sequence.Frames.size(); ++i)
  {
    if (sequence.Frames[i].time == sequence.Frames[i - 1].time)
      throw FileError(seriesPath,
                      "two files share the time " + std::to_string(sequence.Frames[i].time));
  }
  return sequence;
}

FrameSequence FrameSequence::fromFiles(const std::vector<std::string>& paths, double frameInterval)
{
  if (!(frameInterval > 0) || !std::isfinite(frameInterval))
  {
    throw std::invalid_argument("FrameInterval must be a positive number, got " +
                                std::to_string(frameInterval));
  }
  FrameSequence sequence;
  for (std::size_t i = 0; i < paths.size(); ++i)
    sequence.Frames.push_back({paths[i], static_cast<double>(i) * frameInterval});
  return sequence;
}

std::size_t FrameSequence::frameAtTime(double time) const
{
  if (Frames.empty())
    return 0;
  // A little slack so a time that lost its last bit on the way through the pipeline
  // still selects its own frame.
  time += 1e-9 * std::max(1.0, std::abs(time));
  const auto it = std::upper_bound(Frames.begin(), Frames.end(), time,
                                   [](double t, const Frame& f) { return t < f.time; });
  if (it == Frames.begin())
    return 0;
  return static_cast<std::size_t>(it - Frames.begin()) - 1;
}

} // namespace dp

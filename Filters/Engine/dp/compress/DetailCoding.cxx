// SPDX-License-Identifier: BSD-3-Clause
#include "dp/compress/DetailCoding.h"

#include "dp/compress/RangeCoder.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dp
{
namespace
{

using compress::BitModel;
using compress::IntegerModel;

constexpr int Contexts = 3;                  // the parents' residuals: 0, 1, 2 or more steps
constexpr double Limit = 4503599627370496.0; // 2^52 steps

/** What encoder and decoder keep from frame to frame: both frames' decoded values and codes,
 *  and the adaptive models. */
class Hierarchy
{
public:
  explicit Hierarchy(const SubdivisionMap& map)
      : Map(map), Fine(map.fineVertices()), Current(Fine, 0.0), Previous(Fine, 0.0), Codes(Fine, 0),
        PreviousCodes(Fine, 0), Models(static_cast<std::size_t>(map.levels() + 1) * Contexts),
        Choice(static_cast<std::size_t>(map.levels() + 1))
  {
  }

  std::size_t begin(int level) const { return level == 0 ? 0 : Map.verticesOf(level - 1); }
  std::size_t end(int level) const { return Map.verticesOf(level); }
  int levels() const { return Map.levels(); }

  /** The spatial prediction of vertex i (level >= 1: its parents' mean in `values`). */
  double spatial(const std::vector<double>& values, std::size_t i) const
  {
    if (i < Map.baseVertices())
      return 0.0;
    const auto& p = Map.parents()[i - Map.baseVertices()];
    return 0.5 * (values[static_cast<std::size_t>(p[0])] + values[static_cast<std::size_t>(p[1])]);
  }
  /** Vertex i's prediction, temporal or not. */
  double predicted(std::size_t i, bool temporal) const
  {
    const double s = spatial(Current, i);
    return temporal ? s + Previous[i] - spatial(Previous, i) : s;
  }
  /** The model vertex i's residual is coded with. */
  IntegerModel& model(int level, std::size_t i)
  {
    std::int64_t activity;
    if (i < Map.baseVertices())
      activity = std::abs(PreviousCodes[i]);
    else
    {
      const auto& p = Map.parents()[i - Map.baseVertices()];
      activity = std::abs(Codes[static_cast<std::size_t>(p[0])]) +
                 std::abs(Codes[static_cast<std::size_t>(p[1])]);
    }
    const auto context = static_cast<std::size_t>(std::min<std::int64_t>(activity, Contexts - 1));
    return Models[static_cast<std::size_t>(level) * Contexts + context];
  }
  BitModel& choice(int level) { return Choice[static_cast<std::size_t>(level)]; }
  void set(std::size_t i, double predictedValue, std::int64_t code, double step)
  {
    Codes[i] = code;
    Current[i] = predictedValue + static_cast<double>(code) * step;
  }
  /** The frame is done: it becomes the previous one. */
  void nextFrame()
  {
    std::swap(Current, Previous);
    std::swap(Codes, PreviousCodes);
  }
  const std::vector<double>& previous() const { return Previous; }

private:
  const SubdivisionMap& Map;
  std::size_t Fine;
  std::vector<double> Current, Previous;
  std::vector<std::int64_t> Codes, PreviousCodes;
  std::vector<IntegerModel> Models;
  std::vector<BitModel> Choice;
};

std::int64_t quantised(double given, double prediction, double step)
{
  const double q = (given - prediction) / step;
  if (!(std::abs(q) < Limit))
    throw std::invalid_argument("detail layer: a displacement (" + std::to_string(given) +
                                ") is not within 2^52 steps of its prediction");
  return static_cast<std::int64_t>(std::llround(q));
}

// What coding a level's residuals would cost, in about bits.
double levelCost(const Hierarchy& h, const double* given, int level, bool temporal, double step)
{
  double cost = 0;
  for (std::size_t i = h.begin(level); i < h.end(level); ++i)
    cost += std::log2(1.0 + 2.0 * std::abs(static_cast<double>(
                                      quantised(given[i], h.predicted(i, temporal), step))));
  return cost;
}

// One frame: each level's predictor chosen and its residuals quantised (and coded when an
// encoder is given).
void encodeFrame(Hierarchy& h, const double* given, double step, bool first,
                 compress::RangeEncoder* encoder)
{
  for (int level = 0; level <= h.levels(); ++level)
  {
    const bool temporal =
        !first && levelCost(h, given, level, true, step) < levelCost(h, given, level, false, step);
    if (encoder && !first)
      encoder->bit(h.choice(level), temporal ? 1 : 0);
    for (std::size_t i = h.begin(level); i < h.end(level); ++i)
    {
      const double prediction = h.predicted(i, temporal);
      const std::int64_t code = quantised(given[i], prediction, step);
      if (encoder)
        encoder->integer(h.model(level, i), code);
      h.set(i, prediction, code, step);
    }
  }
}

void checkStep(double step)
{
  if (!(step > 0) || !std::isfinite(step))
    throw std::invalid_argument("detail layer: the quantisation step must be > 0, not " +
                                std::to_string(step));
}

// Every frame quantised in turn, coded by `encoder` when one is given, the decoded values into
// `decoded` when given.
void encodeFrames(const SubdivisionMap& map, const double* given, std::size_t frames, double step,
                  compress::RangeEncoder* encoder, std::vector<double>* decoded)
{
  checkStep(step);
  const std::size_t n = map.fineVertices();
  Hierarchy h(map);
  if (decoded)
    decoded->resize(n * frames);
  for (std::size_t t = 0; t < frames; ++t)
  {
    encodeFrame(h, given + n * t, step, t == 0, encoder);
    h.nextFrame();
    if (decoded)
      std::copy(h.previous().begin(), h.previous().end(), decoded->begin() + n * t);
  }
}

} // namespace

std::vector<double> quantiseDetail(const SubdivisionMap& map, const double* given,
                                   std::size_t frames, double step)
{
  std::vector<double> decoded;
  encodeFrames(map, given, frames, step, nullptr, &decoded);
  return decoded;
}

std::vector<std::uint8_t> encodeDetail(const SubdivisionMap& map, const double* given,
                                       std::size_t frames, double step,
                                       std::vector<double>* decoded)
{
  compress::RangeEncoder encoder;
  encodeFrames(map, given, frames, step, &encoder, decoded);
  return encoder.finish();
}

std::vector<double> decodeDetail(const SubdivisionMap& map, std::size_t frames, double step,
                                 const std::uint8_t* bytes, std::size_t size,
                                 const std::string& what)
{
  checkStep(step);
  const std::size_t n = map.fineVertices();
  Hierarchy h(map);
  compress::RangeDecoder decoder(bytes, size, what);
  std::vector<double> decoded(n * frames);
  for (std::size_t t = 0; t < frames; ++t)
  {
    for (int level = 0; level <= h.levels(); ++level)
    {
      const bool temporal = t > 0 && decoder.bit(h.choice(level)) != 0;
      for (std::size_t i = h.begin(level); i < h.end(level); ++i)
        h.set(i, h.predicted(i, temporal), decoder.integer(h.model(level, i)), step);
    }
    h.nextFrame();
    std::copy(h.previous().begin(), h.previous().end(), decoded.begin() + n * t);
  }
  decoder.finish();
  return decoded;
}

void setDetail(CompressedSequence& sequence, int levels, const std::vector<double>& displacements,
               double step)
{
  const PcaModel& m = sequence.pca.model;
  if (levels < 1 || levels > MaximumDetailLevels)
    throw std::invalid_argument("detail levels must be 1 to " +
                                std::to_string(MaximumDetailLevels) + ", not " +
                                std::to_string(levels));
  const SubdivisionMap map(sequence.triangles, m.vertices, levels);
  if (displacements.size() != map.fineVertices() * m.frames)
    throw std::invalid_argument("the detail layer has " + std::to_string(displacements.size()) +
                                " displacements; " + std::to_string(m.frames) + " frames of " +
                                std::to_string(map.fineVertices()) + " fine vertices need " +
                                std::to_string(map.fineVertices() * m.frames));
  DetailLayer& d = sequence.detail;
  d.levels = levels;
  d.step = step;
  d.payload = encodeDetail(map, displacements.data(), m.frames, step, &d.displacements);
  // The section: levels, step, fine vertex count, payload size, CRC-32, payload.
  sequence.report.detailBytes = 1 + 8 + 8 + 8 + 4 + d.payload.size();
}

void detailedFrame(const CompressedSequence& sequence, const SubdivisionMap& map, std::size_t t,
                   double* fine)
{
  const std::size_t n = map.fineVertices();
  std::vector<double> base(3 * map.baseVertices()), smooth(3 * n), normals(3 * n);
  sequence.pca.model.frame(t, base.data());
  map.subdivide(base.data(), smooth.data(), normals.data());
  displaceAlongNormals(smooth.data(), normals.data(), &sequence.detail.displacements[n * t], n,
                       fine);
}

} // namespace dp

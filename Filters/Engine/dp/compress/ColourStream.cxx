// SPDX-License-Identifier: BSD-3-Clause
#include "dp/compress/ColourStream.h"

#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>

namespace dp
{

namespace
{

// Visits the colour bytes in the stream's channel-major order: `visit(o, i, before)` with o the
// stream's position, i the byte's in the frame-major colours and `before` the same vertex and
// channel's byte in the frame before (none in frame 0).
template <typename Visit>
void channelMajor(std::size_t vertices, std::size_t frames, Visit visit)
{
  const std::size_t frameBytes = 3 * vertices;
  std::size_t o = 0;
  for (std::size_t c = 0; c < 3; ++c)
    for (std::size_t t = 0; t < frames; ++t)
      for (std::size_t v = 0; v < vertices; ++v, ++o)
      {
        const std::size_t i = t * frameBytes + 3 * v + c;
        visit(o, i, t > 0 ? std::optional<std::size_t>(i - frameBytes) : std::nullopt);
      }
}

} // namespace

std::vector<std::uint8_t> compress::colourResiduals(const std::vector<std::uint8_t>& colours,
                                                    std::size_t vertices, std::size_t frames)
{
  std::vector<std::uint8_t> out(colours.size());
  channelMajor(vertices, frames,
               [&](std::size_t o, std::size_t i, std::optional<std::size_t> before) {
                 out[o] = static_cast<std::uint8_t>(colours[i] - (before ? colours[*before] : 0));
               });
  return out;
}

std::vector<std::uint8_t> compress::coloursFromResiduals(const std::vector<std::uint8_t>& residuals,
                                                         std::size_t vertices, std::size_t frames)
{
  std::vector<std::uint8_t> colours(residuals.size());
  channelMajor(vertices, frames,
               [&](std::size_t o, std::size_t i, std::optional<std::size_t> before) {
                 colours[i] =
                     static_cast<std::uint8_t>(residuals[o] + (before ? colours[*before] : 0));
               });
  return colours;
}

void compress::checkColourCount(const PcaModel& m, std::size_t count)
{
  if (count != 0 && count != 3 * m.vertices * m.frames)
    throw std::invalid_argument("the sequence has " + std::to_string(count) + " colour bytes; " +
                                std::to_string(m.frames) + " frames of " +
                                std::to_string(m.vertices) + " vertices need " +
                                std::to_string(3 * m.vertices * m.frames) + " (r g b each)");
}

void holdColours(std::vector<std::uint8_t>& held, const std::vector<std::uint8_t>& colours,
                 int tolerance)
{
  if (held.size() != colours.size())
  {
    held = colours;
    return;
  }
  for (std::size_t i = 0; i < colours.size(); ++i)
    if (std::abs(static_cast<int>(colours[i]) - static_cast<int>(held[i])) > tolerance)
      held[i] = colours[i];
}

void setColours(CompressedSequence& sequence, std::vector<std::uint8_t> colours, int tolerance)
{
  const PcaModel& m = sequence.pca.model;
  compress::checkColourCount(m, colours.size());
  if (tolerance < 0 || tolerance > MaximumColourTolerance)
    throw std::invalid_argument("the colour tolerance must be 0 to " +
                                std::to_string(MaximumColourTolerance) + " levels, not " +
                                std::to_string(tolerance));
  if (tolerance > 0 && !colours.empty())
  {
    const std::size_t frameBytes = 3 * m.vertices;
    std::vector<std::uint8_t> held;
    for (std::size_t t = 0; t < m.frames; ++t)
    {
      const auto frame = colours.begin() + static_cast<std::ptrdiff_t>(t * frameBytes);
      holdColours(held, std::vector<std::uint8_t>(frame, frame + frameBytes), tolerance);
      std::copy(held.begin(), held.end(), frame);
    }
  }
  sequence.colours = std::move(colours);
  sequence.report.colourTolerance = sequence.colours.empty() ? 0 : tolerance;
  sequence.report.colourBytes =
      sequence.colours.empty()
          ? 0
          : compress::colourSectionBytes(sequence.colours, m.vertices, m.frames);
}

} // namespace dp

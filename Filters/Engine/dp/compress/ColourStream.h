// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file ColourStream.h
 * @brief A compressed take's colour: the hold that makes it cheaper to store (setColours,
 *        holdColours) and the residuals its .dpz section codes (colourResiduals).
 *
 * The colour of every vertex in every frame travels beside the geometry as r g b bytes. Stored,
 * each frame is its difference from the frame before, channel by channel; a vertex keeps about its
 * colour from frame to frame, so the differences are small and zstd packs them well. Limits: 8 bits
 * a channel, three channels (no alpha); the hold's tolerance is at most MaximumColourTolerance.
 */
#pragma once

#include "dp/compress/PcaCompression.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dp
{

/** The colour tolerances setColours takes, in levels of 255. */
constexpr int MaximumColourTolerance = 64;

/**
 * Gives `sequence` its colours (frames x vertices x 3 bytes, as CompressedSequence::colours) and
 * sets report.colourBytes to what they take in the file, so a caller can say it before writing.
 * With a `tolerance` over 0 the colours are first made cheaper to store: each channel of each
 * vertex keeps its value from frame to frame while the given colour stays within `tolerance`
 * levels of it, and takes the given value when it departs further. Every stored byte is then
 * within `tolerance` of the given one; the tracked colour's frame-to-frame noise (a vertex's
 * colour is read anew from each frame's points) mostly becomes repeats, which the stream's
 * differences from the previous frame store as zeros, and the colour stops flickering. A real
 * change of colour (a shadow, a turn of the material to the light) still passes, in one step.
 * Throws std::invalid_argument when the count is not frames * vertices * 3 or the tolerance is
 * outside [0, MaximumColourTolerance].
 */
void setColours(CompressedSequence& sequence, std::vector<std::uint8_t> colours, int tolerance = 0);

/** One frame of setColours' hold: `held`, the colours stored for the frame before (empty, or
 *  another size, for the first frame), becomes the colours stored for this frame's `colours`. */
void holdColours(std::vector<std::uint8_t>& held, const std::vector<std::uint8_t>& colours,
                 int tolerance);

namespace compress
{

/** The colour section's bytes before zstd: channel-major (the red of every frame and vertex, then
 *  the green, then the blue), frame 0 as it is and each later frame as its difference (mod 256)
 *  from the same vertex's previous frame. On a tracked take with colour zstd packs them to 63 %
 *  of what it makes of the colours as they are, and the channel-major order to 5 % less than
 *  r g b per vertex. */
std::vector<std::uint8_t> colourResiduals(const std::vector<std::uint8_t>& colours,
                                          std::size_t vertices, std::size_t frames);
/** colourResiduals undone. */
std::vector<std::uint8_t> coloursFromResiduals(const std::vector<std::uint8_t>& residuals,
                                               std::size_t vertices, std::size_t frames);
/** Refuses (std::invalid_argument) colours of a count other than none or three bytes per vertex
 *  and frame of `m`. */
void checkColourCount(const PcaModel& m, std::size_t count);
/** What the colour section of a .dpz takes: its header and the residuals through zstd. */
std::size_t colourSectionBytes(const std::vector<std::uint8_t>& colours, std::size_t vertices,
                               std::size_t frames);

} // namespace compress

} // namespace dp

// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file AnimatedMesh.h
 * @brief Triangle meshes of fixed connectivity whose vertices move over time: the ground truth
 *        the tracker is measured against.
 *
 * Vertex i is the same material point in every frame, so an AnimatedMesh gives exact vertex
 * trajectories. Two procedural animations ship with the product (no downloaded data needed):
 *  - BendingTube: a closed, capped tube that bends into an arc and twists about its axis;
 *  - WavingSheet: a rectangular sheet with an open boundary, a travelling wave like a flag.
 * MeshSequenceFiles reads an animation stored as one mesh file per frame (PLY/OBJ): the
 * connectivity comes from frame 0, and every frame must have frame 0's vertex count.
 *
 * Frames are produced on demand (positions(frame)), so a long animation is never held whole.
 */
#pragma once

#include "dp/io/FrameSequence.h"
#include "dp/io/PointCloud.h"

#include <cstdint>
#include <string>
#include <vector>

namespace dp
{

class AnimatedMesh
{
public:
  virtual ~AnimatedMesh() = default;
  virtual std::size_t numberOfFrames() const = 0;
  virtual std::size_t numberOfVertices() const = 0;
  /** Triangles, 3 vertex indices each; the same for every frame. */
  virtual const std::vector<std::int64_t>& triangles() const = 0;
  /** Vertex positions of one frame, x y z per vertex. */
  virtual std::vector<double> positions(std::size_t frame) const = 0;

  /** One frame as a PointCloud with its triangles (e.g. to write it as a PLY mesh). */
  PointCloud frameMesh(std::size_t frame) const;
};

/** A capped tube (axis z from 0 to length) bending into an arc in the x-z plane and twisting. */
class BendingTube : public AnimatedMesh
{
public:
  struct Options
  {
    std::size_t frames = 30;
    std::size_t rings = 40;    // vertex rings along the axis
    std::size_t segments = 24; // vertices around each ring
    double length = 1.0;
    double radius = 0.12;
    double maxBendRadians = 1.6; // bend angle at the peak of the motion
    double maxTwistRadians = 0.8;
  };
  explicit BendingTube(const Options& options);
  BendingTube() : BendingTube(Options{}) {}
  std::size_t numberOfFrames() const override { return Opts.frames; }
  std::size_t numberOfVertices() const override { return Rest.size() / 3; }
  const std::vector<std::int64_t>& triangles() const override { return Triangles; }
  std::vector<double> positions(std::size_t frame) const override;

private:
  Options Opts;
  std::vector<double> Rest;
  std::vector<std::int64_t> Triangles;
};

/** A sheet over [0,width]x[0,height] in z=0 carrying a wave whose amplitude grows with x. */
class WavingSheet : public AnimatedMesh
{
public:
  struct Options
  {
    std::size_t frames = 30;
    std::size_t columns = 40;
    std::size_t rows = 24;
    double width = 1.0;
    double height = 0.6;
    double amplitude = 0.12;
    double wavelength = 0.8;
  };
  explicit WavingSheet(const Options& options);
  WavingSheet() : WavingSheet(Options{}) {}
  std::size_t numberOfFrames() const override { return Opts.frames; }
  std::size_t numberOfVertices() const override { return Opts.columns * Opts.rows; }
  const std::vector<std::int64_t>& triangles() const override { return Triangles; }
  std::vector<double> positions(std::size_t frame) const override;

private:
  Options Opts;
  std::vector<std::int64_t> Triangles;
};

/** An animation stored as one mesh file per frame (e.g. ../shared/data/horse-gallop). */
class MeshSequenceFiles : public AnimatedMesh
{
public:
  /** Reads frame 0 for the connectivity; throws FileError if it has no faces. */
  explicit MeshSequenceFiles(FrameSequence frames);
  std::size_t numberOfFrames() const override { return Frames.size(); }
  std::size_t numberOfVertices() const override { return VertexCount; }
  const std::vector<std::int64_t>& triangles() const override { return Triangles; }
  /** Reads the frame's file; throws FileError if its vertex count differs from frame 0's. */
  std::vector<double> positions(std::size_t frame) const override;

private:
  FrameSequence Frames;
  std::size_t VertexCount = 0;
  std::vector<std::int64_t> Triangles;
};

/** Splits polygons into triangle fans; throws std::invalid_argument on a face < 3 vertices. */
std::vector<std::int64_t> triangulateFaces(const PointCloud& mesh);

} // namespace dp

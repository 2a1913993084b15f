// SPDX-License-Identifier: BSD-3-Clause
// Draco (.drc) frames: read as Draco's own decoder gives them, for every way its encoder writes a
// mesh or a point cloud; written so that Draco reads them; bad files refused by name.
#include "TestUtilities.h"

#include "dp/io/AnimatedMesh.h"
#include "dp/io/PointCloudIO.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace
{

using dp::test::expectFileError;
using dp::test::TempDir;

// The bending tube's first frame with normals and a colour per vertex (alpha when asked).
dp::PointCloud colouredTube(int colourComponents)
{
  const dp::BendingTube tube;
  dp::PointCloud cloud;
  cloud.points = tube.positions(0);
  const std::size_t n = cloud.numberOfPoints();
  for (std::size_t i = 0; i < n; ++i)
  {
    const double* p = &cloud.points[3 * i];
    const double r = std::max(std::hypot(p[0], p[1]), 1e-9);
    cloud.normals.insert(cloud.normals.end(), {float(p[0] / r), float(p[1] / r), 0.f});
    for (int c = 0; c < colourComponents; ++c)
      cloud.colors.push_back(static_cast<std::uint8_t>((37 * i + 91 * c) % 256));
  }
  cloud.colorComponents = colourComponents;
  const std::vector<std::int64_t>& triangles = tube.triangles();
  for (std::size_t f = 0; f < triangles.size(); f += 3)
    cloud.addFace(&triangles[f], 3);
  return cloud;
}

// A Draco geometry from a cloud, by hand through the library (as a capture tool would).
std::unique_ptr<draco::PointCloud> toDraco(const dp::PointCloud& cloud, bool mesh,
                                           bool floatColours)
{
  std::unique_ptr<draco::PointCloud> out =
      mesh ? std::make_unique<draco::Mesh>() : std::make_unique<draco::PointCloud>();
  const std::size_t n = cloud.numberOfPoints();
  out->set_num_points(static_cast<std::uint32_t>(n));
  const auto add = [&](draco::GeometryAttribute::Type type, int components, draco::DataType data,
                       int bytes, const auto& valueOf)
  {
    draco::GeometryAttribute a;
    a.Init(type, nullptr, components, data, data == draco::DT_UINT8, bytes * components, 0);
    draco::PointAttribute* stored = out->attribute(out->AddAttribute(a, true, n));
    for (std::size_t i = 0; i < n; ++i)
    {
      const auto value = valueOf(i);
      stored->SetAttributeValue(draco::AttributeValueIndex(i), value.data());
    }
  };
  add(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32, 4,
      [&](std::size_t i)
      {
        return std::array<float, 3>{float(cloud.points[3 * i]), float(cloud.points[3 * i + 1]),
                                    float(cloud.points[3 * i + 2])};
      });
  add(draco::GeometryAttribute::NORMAL, 3, draco::DT_FLOAT32, 4,
      [&](std::size_t i)
      {
        return std::array<float, 3>{cloud.normals[3 * i], cloud.normals[3 * i + 1],
                                    cloud.normals[3 * i + 2]};
      });
  const int k = cloud.colorComponents;
  if (floatColours)
    add(draco::GeometryAttribute::COLOR, 3, draco::DT_FLOAT32, 4,
        [&](std::size_t i)
        {
          return std::array<float, 3>{cloud.colors[k * i] / 255.f, cloud.colors[k * i + 1] / 255.f,
                                      cloud.colors[k * i + 2] / 255.f};
        });
  else
    add(draco::GeometryAttribute::COLOR, k, draco::DT_UINT8, 1,
        [&](std::size_t i)
        {
          std::array<std::uint8_t, 4> c{0, 0, 0, 0};
          std::copy(&cloud.colors[k * i], &cloud.colors[k * i] + k, c.begin());
          return c;
        });
  if (mesh)
    for (std::size_t f = 0; f < cloud.numberOfFaces(); ++f)
    {
      const std::int64_t* t = &cloud.faceConnectivity[3 * f];
      static_cast<draco::Mesh*>(out.get())->AddFace({draco::PointIndex(std::uint32_t(t[0])),
                                                     draco::PointIndex(std::uint32_t(t[1])),
                                                     draco::PointIndex(std::uint32_t(t[2]))});
    }
  return out;
}

std::string encode(const draco::PointCloud& geometry, bool mesh, int method)
{
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, 12);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, 10); // the kd-tree wants it
  encoder.SetEncodingMethod(method);
  draco::EncoderBuffer buffer;
  const draco::Status status =
      mesh ? encoder.EncodeMeshToBuffer(static_cast<const draco::Mesh&>(geometry), &buffer)
           : encoder.EncodePointCloudToBuffer(geometry, &buffer);
  EXPECT_TRUE(status.ok()) << status.error_msg_string();
  return std::string(buffer.data(), buffer.size());
}

// What Draco's own decoder gives for these bytes.
std::unique_ptr<draco::PointCloud> decodeWithDraco(const std::string& bytes, bool mesh)
{
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::Decoder decoder;
  if (mesh)
    return std::move(decoder.DecodeMeshFromBuffer(&buffer)).value();
  return std::move(decoder.DecodePointCloudFromBuffer(&buffer)).value();
}

struct Encoding
{
  const char* name;
  bool mesh;
  int method;
  bool floatColours;
  int colourComponents;
};

class DracoEncodings : public ::testing::TestWithParam<Encoding>
{
};

TEST_P(DracoEncodings, FramesReadBackAsDracosDecoderGivesThem)
{
  const Encoding e = GetParam();
  TempDir dir;
  const std::string path = dir.file(std::string(e.name) + ".drc");
  const dp::PointCloud source = colouredTube(e.colourComponents);
  const std::string bytes = encode(*toDraco(source, e.mesh, e.floatColours), e.mesh, e.method);
  dp::test::writeText(path, bytes);
  const dp::PointCloud read = dp::readPointCloud(path);
  const std::unique_ptr<draco::PointCloud> reference = decodeWithDraco(bytes, e.mesh);

  ASSERT_EQ(read.numberOfPoints(), reference->num_points());
  const auto* position = reference->GetNamedAttribute(draco::GeometryAttribute::POSITION);
  const auto* normal = reference->GetNamedAttribute(draco::GeometryAttribute::NORMAL);
  for (draco::PointIndex i(0); i < reference->num_points(); ++i)
  {
    float p[3], n[3];
    position->ConvertValue<float>(position->mapped_index(i), 3, p);
    normal->ConvertValue<float>(normal->mapped_index(i), 3, n);
    for (int c = 0; c < 3; ++c)
    {
      ASSERT_EQ(read.points[3 * i.value() + c], double(p[c])) << "point " << i.value();
      ASSERT_EQ(read.normals[3 * i.value() + c], n[c]) << "normal " << i.value();
    }
  }
  // The colours exactly as written (float channels to the nearest level), matched by position:
  // Draco orders the points its own way.
  ASSERT_EQ(read.colorComponents, e.floatColours ? 3 : e.colourComponents);
  std::map<std::array<double, 3>, std::size_t> sourceIndex;
  for (std::size_t i = 0; i < source.numberOfPoints(); ++i)
    sourceIndex[{source.points[3 * i], source.points[3 * i + 1], source.points[3 * i + 2]}] = i;
  const double step = 2.5 / 4096; // 12 bits over the tube's extent, with room
  std::size_t matched = 0;
  for (std::size_t i = 0; i < read.numberOfPoints(); ++i)
  {
    double best = 1e9;
    std::size_t closest = 0;
    for (const auto& [p, j] : sourceIndex)
    {
      const double d = std::hypot(p[0] - read.points[3 * i], p[1] - read.points[3 * i + 1],
                                  p[2] - read.points[3 * i + 2]);
      if (d < best)
        best = d, closest = j;
    }
    ASSERT_LT(best, step) << "point " << i << " is not a point of the source";
    const int k = read.colorComponents;
    matched += std::equal(&read.colors[k * i], &read.colors[k * i] + k,
                          &source.colors[source.colorComponents * closest]);
  }
  // Points closer than the quantisation step may swap colours; the tube's are not.
  EXPECT_EQ(matched, read.numberOfPoints());
  // Triangles: as Draco's decoder gives them.
  if (e.mesh)
  {
    const auto& mesh = static_cast<const draco::Mesh&>(*reference);
    ASSERT_EQ(read.numberOfFaces(), mesh.num_faces());
    ASSERT_EQ(read.numberOfFaces(), source.numberOfFaces());
    for (draco::FaceIndex f(0); f < mesh.num_faces(); ++f)
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(read.faceConnectivity[3 * f.value() + c], mesh.face(f)[c].value());
  }
  else
    EXPECT_EQ(read.numberOfFaces(), 0u);
}

INSTANTIATE_TEST_SUITE_P(
    Draco, DracoEncodings,
    ::testing::Values(
        Encoding{"MeshEdgebreaker", true, draco::MESH_EDGEBREAKER_ENCODING, false, 3},
        Encoding{"MeshSequential", true, draco::MESH_SEQUENTIAL_ENCODING, false, 4},
        Encoding{"MeshFloatColours", true, draco::MESH_EDGEBREAKER_ENCODING, true, 3},
        Encoding{"PointsKdTree", false, draco::POINT_CLOUD_KD_TREE_ENCODING, false, 3},
        Encoding{"PointsSequential", false, draco::POINT_CLOUD_SEQUENTIAL_ENCODING, false, 4}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(DracoFormat, WrittenFramesReadBackWithinTheQuantisation)
{
  TempDir dir;
  const dp::PointCloud mesh = colouredTube(3);
  dp::PointCloud points = mesh;
  points.faceOffsets.clear();
  points.faceConnectivity.clear();
  for (const auto& [name, source] : {std::pair{"mesh.drc", &mesh}, {"points.drc", &points}})
  {
    dp::writePointCloud(dir.file(name), *source);
    const dp::PointCloud read = dp::readPointCloud(dir.file(name));
    ASSERT_EQ(read.numberOfPoints(), source->numberOfPoints()) << name;
    EXPECT_EQ(read.numberOfFaces(), source->numberOfFaces()) << name;
    EXPECT_EQ(read.colorComponents, 3);
    // Every read point is one of the source's within 14 bits of the largest side (2.5 m).
    double worst = 0;
    for (std::size_t i = 0; i < read.numberOfPoints(); ++i)
    {
      double best = 1e9;
      for (std::size_t j = 0; j < source->numberOfPoints(); ++j)
        best = std::min(best, std::hypot(source->points[3 * j] - read.points[3 * i],
                                         source->points[3 * j + 1] - read.points[3 * i + 1],
                                         source->points[3 * j + 2] - read.points[3 * i + 2]));
      worst = std::max(worst, best);
    }
    EXPECT_LT(worst, 2.5 / 16384) << name;
    EXPECT_GT(worst, 0) << name << ": quantised, so not bit for bit";
  }
}

TEST(DracoFormat, TruncatedOrCorruptFilesAreRefusedByNameNeverACrash)
{
  TempDir dir;
  dp::writePointCloud(dir.file("good.drc"), colouredTube(3));
  const std::string bytes = dp::test::readText(dir.file("good.drc"));
  const std::string path = dir.file("bad.drc");
  std::size_t refused = 0, cuts = 0;
  for (std::size_t length = 0; length < bytes.size(); length += 1 + length / 16, ++cuts)
  {
    dp::test::writeText(path, bytes.substr(0, length));
    try
    {
      dp::readPointCloud(path);
    }
    catch (const dp::FileError& e)
    {
      EXPECT_EQ(std::string(e.what()).rfind(path, 0), 0u) << e.what();
      ++refused;
    }
  }
  // Every cut inside the header and the connectivity is refused; Draco may decode a file cut
  // inside its last attribute's entropy-coded tail.
  EXPECT_GE(refused, cuts * 9 / 10);
  expectFileError([&] { dp::readPointCloud(path); }, path, "");
  dp::test::writeText(path, "");
  expectFileError([&] { dp::readPointCloud(path); }, path, "no Draco header");
  dp::test::writeText(path, "PLY but named .drc");
  expectFileError([&] { dp::readPointCloud(path); }, path, "no Draco header");
  // A byte changed anywhere: refused by name or read, never a crash.
  for (std::size_t at = 0; at < bytes.size(); at += 7)
  {
    std::string corrupt = bytes;
    corrupt[at] = static_cast<char>(corrupt[at] ^ 0x5a);
    dp::test::writeText(path, corrupt);
    try
    {
      const dp::PointCloud read = dp::readPointCloud(path);
      read.validate();
    }
    catch (const dp::FileError& e)
    {
      EXPECT_EQ(std::string(e.what()).rfind(path, 0), 0u) << e.what();
    }
  }
}

TEST(DracoFormat, CountsBeyondTheFileOrTheMemoryBudgetAreRefusedBeforeDecoding)
{
  TempDir dir;
  const std::string path = dir.file("claims.drc");
  // An edgebreaker mesh (bitstream 2.2) claiming 700 million faces and 100 million vertices in
  // 25 bytes: Draco's decoder would size its corner table (tens of GB) before reading further.
  const std::string header =
      std::string("DRACO") + '\x02' + '\x02' + '\x01' + '\x01' + std::string(2, '\0') + '\x00';
  const auto varint = [](std::uint32_t v)
  {
    std::string out;
    for (; v >= 0x80; v >>= 7)
      out += static_cast<char>((v & 0x7f) | 0x80);
    return out + static_cast<char>(v);
  };
  dp::test::writeText(path, header + varint(100000000) + varint(700000000) + std::string(4, '\0'));
  expectFileError([&] { dp::readPointCloud(path); }, path,
                  "declares 100000000 points and 700000000 faces in 25 bytes");
  // A kd-tree point cloud claiming 655 360 points in 33 bytes (a fuzzer's finding: its attribute
  // then declared 255 components a point, and Draco asked for 668 MB).
  const std::string finding = std::string("DRACO") + '\x02' + '\x03' + '\x00' + '\x01' +
                              std::string(2, '\0') + std::string("\x00\x00\x0a\x00", 4) +
                              std::string(18, '\x01');
  dp::test::writeText(path, finding);
  expectFileError([&] { dp::readPointCloud(path); }, path, "more than any coding holds");
  // A kd-tree point cloud of bitstream 2.2 declaring 10 points in its header and 503 971 840 in
  // its attribute data, which Draco sizes the attribute by (a fuzzer's finding: 6 GB asked for):
  // Draco's encoder writes the same count twice.
  const std::string oldKdTree =
      std::string("DRACO") + '\x02' + '\x02' + '\x00' + '\x01' + std::string(2, '\0') +
      std::string("\x0a\x00\x00\x00", 4) + '\x01' + '\x01' + std::string("\x00\x09\x03\x00", 4) +
      '\x00' + '\x00' + '\x00' + std::string("\x00\x00\x0a\x1e", 4) + std::string(16, '\x01');
  dp::test::writeText(path, oldKdTree);
  expectFileError([&] { dp::readPointCloud(path); }, path,
                  "its two point counts differ (10 and 503971840)");
  // The same stream whose second count is 0 (a fuzzer's finding: Draco then read the 10 points'
  // positions from an attribute of none, undefined behaviour inside Draco).
  std::string noneAgain = oldKdTree;
  std::fill(noneAgain.begin() + 24, noneAgain.begin() + 28, '\0');
  dp::test::writeText(path, noneAgain);
  expectFileError([&] { dp::readPointCloud(path); }, path,
                  "its two point counts differ (10 and 0)");
  // An honest file over the budget: refused by its counts, before the library decodes it.
  dp::writePointCloud(path, colouredTube(3));
  ::setenv("DP_MEMORY_BUDGET", "64K", 1);
  expectFileError([&] { dp::readPointCloud(path); }, path, "more than the memory budget of 64 KiB");
  ::unsetenv("DP_MEMORY_BUDGET");
  EXPECT_EQ(dp::readPointCloud(path).numberOfPoints(), colouredTube(3).numberOfPoints());
  // A bitstream version this build does not know.
  dp::test::writeText(path, std::string("DRACO") + '\x09' + '\x00' + '\x01' + '\x01' +
                                std::string(8, '\0'));
  expectFileError([&] { dp::readPointCloud(path); }, path, "bitstream version 9.0");
}

} // namespace

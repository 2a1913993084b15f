// SPDX-License-Identifier: BSD-3-Clause
// Engine readers and writers: every format, both directions, and every kind of bad file.
#include "TestUtilities.h"

#include "dp/io/PlyHeader.h"
#include "dp/io/PointCloudIO.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

namespace
{

using dp::test::expectFileError;
using dp::test::TempDir;
using dp::test::writeText;

dp::PointCloud sampleCloud(bool withFaces)
{
  dp::PointCloud c;
  c.points = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1.5};
  c.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 1, 0, 0};
  c.colorComponents = 3;
  c.colors = {255, 0, 0, 0, 255, 0, 0, 0, 255, 10, 20, 30};
  c.attributes.push_back({"intensity", 1, {0.5f, 1.5f, 2.5f, 3.5f}});
  if (withFaces)
  {
    const std::int64_t f0[3] = {0, 1, 2}, f1[4] = {0, 1, 3, 2};
    c.addFace(f0, 3);
    c.addFace(f1, 4);
  }
  return c;
}

void expectSameCloud(const dp::PointCloud& a, const dp::PointCloud& b, bool colors = true,
                     bool attributes = true)
{
  ASSERT_EQ(a.numberOfPoints(), b.numberOfPoints());
  for (std::size_t i = 0; i < a.points.size(); ++i)
    EXPECT_NEAR(a.points[i], b.points[i], 1e-6) << "coordinate " << i;
  ASSERT_EQ(a.normals.size(), b.normals.size());
  for (std::size_t i = 0; i < a.normals.size(); ++i)
    EXPECT_NEAR(a.normals[i], b.normals[i], 1e-6);
  if (colors)
  {
    EXPECT_EQ(a.colorComponents, b.colorComponents);
    EXPECT_EQ(a.colors, b.colors);
  }
  if (attributes)
  {
    ASSERT_EQ(a.attributes.size(), b.attributes.size());
    for (std::size_t k = 0; k < a.attributes.size(); ++k)
    {
      EXPECT_EQ(a.attributes[k].name, b.attributes[k].name);
      EXPECT_EQ(a.attributes[k].values, b.attributes[k].values);
    }
  }
  EXPECT_EQ(a.faceOffsets, b.faceOffsets);
  EXPECT_EQ(a.faceConnectivity, b.faceConnectivity);
}

class PlyEncodings : public ::testing::TestWithParam<dp::PlyEncoding>
{
};

TEST_P(PlyEncodings, RoundTripKeepsEveryArrayAndFace)
{
  TempDir dir;
  const std::string path = dir.file("cloud.ply");
  const dp::PointCloud cloud = sampleCloud(true);
  dp::writePLY(path, cloud, GetParam());
  expectSameCloud(cloud, dp::readPLY(path));
}

INSTANTIATE_TEST_SUITE_P(AllEncodings, PlyEncodings,
                         ::testing::Values(dp::PlyEncoding::Ascii,
                                           dp::PlyEncoding::BinaryLittleEndian,
                                           dp::PlyEncoding::BinaryBigEndian));

// Writes each (file text, expected message part) case to `path` and expects `read` to refuse it
// with an error naming the file.
template <std::size_t N>
void expectEachRefused(const std::string& path,
                       const std::pair<std::string, std::string> (&cases)[N],
                       dp::PointCloud (*read)(const std::string&))
{
  for (const auto& [text, expected] : cases)
  {
    writeText(path, text);
    expectFileError([&] { read(path); }, path, expected);
  }
}

TEST(PLY, ReadsHandWrittenAsciiWithDoublesListsAndExtraElements)
{
  TempDir dir;
  const std::string path = dir.file("hand.ply");
  writeText(path, "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\n"
                  "element vertex 3\r\nproperty double x\r\nproperty double y\r\n"
                  "property double z\r\nproperty list uchar int extra\r\n"
                  "property float quality\r\n"
                  "element face 1\r\nproperty list uchar uint vertex_index\r\n"
                  "element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\n"
                  "end_header\r\n"
                  "0.25 0 0 2 7 8 0.5\r\n1 0 0 0 1.5\r\n0 1 -3e2 1 9 2.5\r\n3 0 1 2\r\n0 1\r\n");
  const dp::PointCloud c = dp::readPLY(path);
  ASSERT_EQ(c.numberOfPoints(), 3u);
  EXPECT_DOUBLE_EQ(c.points[0], 0.25);
  EXPECT_DOUBLE_EQ(c.points[8], -300.0);
  ASSERT_EQ(c.attributes.size(), 1u);
  EXPECT_EQ(c.attributes[0].name, "quality");
  EXPECT_FLOAT_EQ(c.attributes[0].values[2], 2.5f);
  ASSERT_EQ(c.numberOfFaces(), 1u);
  EXPECT_EQ(c.faceConnectivity, (std::vector<std::int64_t>{0, 1, 2}));
}

TEST(PLY, TruncatedBinaryBodyIsAnErrorNamingTheFile)
{
  TempDir dir;
  const std::string path = dir.file("cut.ply");
  dp::writePLY(path, sampleCloud(true), dp::PlyEncoding::BinaryLittleEndian);
  const std::string whole = dp::test::readText(path);
  // Cut inside the vertex block, then inside the face block.
  for (std::size_t cut : {whole.size() - 30, whole.size() - 3})
  {
    writeText(path, whole.substr(0, cut));
    expectFileError([&] { dp::readPLY(path); }, path, "truncated");
  }
}

TEST(PLY, TruncatedAsciiBodyIsAnError)
{
  TempDir dir;
  const std::string path = dir.file("cut.ply");
  writeText(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                  "property float z\nend_header\n0 0 0\n1 1 1\n");
  expectFileError([&] { dp::readPLY(path); }, path, "truncated");
}

TEST(PlyHeader, ParsesEveryTypeNameListsAndWhereTheBodyStarts)
{
  // Both names of each type, a list, comments and obj_info, "\r\n" line ends and a binary body
  // that begins with bytes a line reader would mistake for text: the body starts right after
  // "end_header" and its line end, wherever those are.
  const std::string header =
      "ply\r\nformat binary_big_endian 1.0\r\ncomment two names per type\r\nobj_info x\r\n"
      "element vertex 7\r\nproperty char a\r\nproperty uint8 b\r\nproperty short c\r\n"
      "property uint16 d\r\nproperty int32 e\r\nproperty uint f\r\nproperty float32 g\r\n"
      "property double h\r\n\r\nelement face 0\r\nproperty list uchar int vertex_indices\r\n"
      "end_header\r\n";
  const std::string bytes = header + std::string("\nend_header\n\0\x01", 14);
  const dp::support::PlyHeader h = dp::support::parsePlyHeader("cube.ply", bytes);
  EXPECT_EQ(h.encoding, dp::support::PlyBodyEncoding::Big);
  EXPECT_EQ(h.bodyOffset, header.size());
  ASSERT_EQ(h.elements.size(), 2u);
  EXPECT_EQ(h.elements[0].name, "vertex");
  EXPECT_EQ(h.elements[0].count, 7u);
  using T = dp::support::PlyType;
  const T types[] = {T::Int8,  T::UInt8,  T::Int16,   T::UInt16,
                     T::Int32, T::UInt32, T::Float32, T::Float64};
  const std::size_t sizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  ASSERT_EQ(h.elements[0].properties.size(), 8u);
  for (std::size_t p = 0; p < 8; ++p)
  {
    const dp::support::PlyProperty& property = h.elements[0].properties[p];
    EXPECT_EQ(property.name, std::string(1, static_cast<char>('a' + p)));
    EXPECT_EQ(property.type, types[p]) << property.name;
    EXPECT_FALSE(property.isList);
    EXPECT_EQ(dp::support::sizeOf(property.type), sizes[p]) << property.name;
  }
  EXPECT_EQ(h.elements[1].name, "face");
  EXPECT_EQ(h.elements[1].count, 0u);
  ASSERT_EQ(h.elements[1].properties.size(), 1u);
  EXPECT_TRUE(h.elements[1].properties[0].isList);
  EXPECT_EQ(h.elements[1].properties[0].countType, T::UInt8);
  EXPECT_EQ(h.elements[1].properties[0].type, T::Int32);
  EXPECT_EQ(h.elements[1].properties[0].name, "vertex_indices");

  for (const auto& [format, encoding] :
       {std::pair{"ascii", dp::support::PlyBodyEncoding::Ascii},
        std::pair{"binary_little_endian", dp::support::PlyBodyEncoding::Little}})
  {
    const std::string text = std::string("ply\nformat ") + format + " 1.0\nend_header\n";
    const dp::support::PlyHeader other = dp::support::parsePlyHeader("f.ply", text);
    EXPECT_EQ(other.encoding, encoding) << format;
    EXPECT_TRUE(other.elements.empty());
    EXPECT_EQ(other.bodyOffset, text.size());
  }
}

TEST(PlyHeader, RefusesEachFaultNamingTheFileAndTheLine)
{
  // (header, the message's part): the line number counts "ply" as line 1.
  const std::pair<std::string, std::string> cases[] = {
      {"", "not a PLY file"},
      {"PLY\nformat ascii 1.0\nend_header\n", "not a PLY file"},
      {"ply\nformat ascii 1.0\nelement vertex 1\n", "no 'end_header' line"},
      {"ply\nelement vertex 0\nend_header\n", "no 'format' line"},
      {"ply\nformat ebcdic 1.0\nend_header\n", "PLY header line 2: unknown format 'ebcdic'"},
      {"ply\nformat ascii 1.0\ncolour red\nend_header\n",
       "PLY header line 3: unknown keyword 'colour'"},
      {"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n",
       "PLY header line 3: malformed element line 'element vertex -1'"},
      {"ply\nformat ascii 1.0\nelement vertex 2.5\nend_header\n", "malformed element line"},
      {"ply\nformat ascii 1.0\nelement vertex\nend_header\n", "malformed element line"},
      {"ply\nformat ascii 1.0\nelement\nend_header\n", "malformed element line"},
      {"ply\nformat ascii 1.0\nelement vertex 2251799813685248\nend_header\n",
       "malformed element line"}, // 2^51, beyond LargestCount
      {"ply\nformat ascii 1.0\nelement vertex nan\nend_header\n", "malformed element line"},
      {"ply\nformat ascii 1.0\nproperty float x\nend_header\n",
       "PLY header line 3: property before any element"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty quaternion x\nend_header\n",
       "PLY header line 4: unknown property type 'quaternion'"},
      {"ply\nformat ascii 1.0\nelement face 1\nproperty list word int v\nend_header\n",
       "PLY header line 4: unknown list count type in 'property list word int v'"},
      {"ply\nformat ascii 1.0\nelement face 1\nproperty list uchar long v\nend_header\n",
       "unknown property type 'long'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float\nend_header\n",
       "PLY header line 4: property without a name"},
  };
  for (const auto& [text, expected] : cases)
    expectFileError([&] { dp::support::parsePlyHeader("some/dir/bad.ply", text); },
                    "some/dir/bad.ply", expected);
}

TEST(PLY, MalformedFilesAreErrorsNamingTheFile)
{
  TempDir dir;
  const std::string path = dir.file("bad.ply");
  const std::pair<std::string, std::string> cases[] = {
      {"not a ply at all", "not a PLY file"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "end_header"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 "
       "2\n",
       "lacks one of the properties x, y, z"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty quaternion x\nend_header\n",
       "unknown property type"},
      {"ply\nformat ebcdic 1.0\nend_header\n", "unknown format"},
      {"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty "
       "float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 1 1\n3 0 1 "
       "7\n",
       "uses vertex 7"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty "
       "float z\n"
       "end_header\n0 zero 0\n",
       "is not a number"},
  };
  expectEachRefused(path, cases, dp::readPLY);
}

// Inputs a coverage-guided fuzzer (issue 15) turned up: numbers whose conversion to an integer
// was undefined behaviour (then a loop of about 2^64 steps). Each is refused, naming the file.
TEST(FuzzFindings, PlyListLengthThatIsNotACountIsAnError)
{
  TempDir dir;
  const std::string path = dir.file("list.ply");
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty "
                           "float y\nproperty float z\nelement face 1\nproperty list uchar int "
                           "vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  for (const char* length : {"-90.35", "2.5", "1e300", "nan", "99"})
  {
    writeText(path, head + length + " 0 1 2\n");
    expectFileError([&] { dp::readPLY(path); }, path, "list length");
  }
  // The same in an element that is skipped (not a face), and in a binary file (a negative char).
  writeText(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                  "property float z\nelement extra 1\nproperty list char int stuff\nend_header\n"
                  "0 0 0\n-3 1 2 3\n");
  expectFileError([&] { dp::readPLY(path); }, path, "list length");
  std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
                       "property float y\nproperty float z\nelement face 1\nproperty list char "
                       "int vertex_indices\nend_header\n";
  binary += std::string(12, '\0') + std::string(1, static_cast<char>(-3)) + std::string(12, '\0');
  writeText(path, binary);
  expectFileError([&] { dp::readPLY(path); }, path, "list length");
}

TEST(FuzzFindings, PlyVertexListsNanColoursAndASecondVertexElement)
{
  TempDir dir;
  const std::string path = dir.file("vertex.ply");
  const std::string xyz = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty "
                          "float y\nproperty float z\n";
  // A list in the vertex element whose length is negative.
  writeText(path, xyz + "property list char int extra\nend_header\n0 0 0 -33 1\n");
  expectFileError([&] { dp::readPLY(path); }, path, "list length");
  // Float colour channels that are NaN read as black (clamping keeps a NaN; casting it was
  // undefined), the others as they are.
  writeText(path, xyz + "property float red\nproperty float green\nproperty float blue\n"
                        "end_header\n0 0 0 nan 1 0\n");
  const dp::PointCloud cloud = dp::readPLY(path);
  ASSERT_EQ(cloud.colorComponents, 3);
  EXPECT_EQ(cloud.colors[0], 0);
  EXPECT_EQ(cloud.colors[1], 255);
  EXPECT_EQ(cloud.colors[2], 0);
  // A second vertex element used to overwrite the points but not the normals: an overflow later.
  writeText(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float "
                  "y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float "
                  "nz\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                  "end_header\n0 0 0 0 0 1\n1 1 1\n2 2 2\n");
  expectFileError([&] { dp::readPLY(path); }, path, "more than one 'vertex' element");
  // A face index far out of range or NaN is refused (printing or casting it was undefined).
  for (const char* index : {"8.9e113", "nan"})
  {
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float "
                    "y\nproperty float z\nelement face 1\nproperty list uchar double "
                    "vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 " +
                        std::string(index) + "\n");
    expectFileError([&] { dp::readPLY(path); }, path, "uses vertex");
  }
  // An element without properties declaring 10^11 items reads at once (it used to hang).
  writeText(path, xyz + "element empty 106010910371\nend_header\n1 2 3\n");
  EXPECT_EQ(dp::readPLY(path).numberOfPoints(), 1u);
}

TEST(FuzzFindings, PlyWithASecondFaceElementIsAnError)
{
  // A second face element restarted the face offsets inside the connectivity; with a NaN point
  // to drop, the renumbering then read far outside its table (found after 3.2 M executions).
  TempDir dir;
  const std::string path = dir.file("faces.ply");
  writeText(path, "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n"
                  "1 0 0\n0 1 0\nnan 0 1\n3 0 1 2\n3 1 2 0\n");
  expectFileError([&] { dp::readPointCloud(path); }, path, "more than one 'face' element");
}

TEST(FuzzFindings, ElementAndPointCountsThatAreNotCountsAreErrors)
{
  TempDir dir;
  const std::string ply = dir.file("count.ply");
  writeText(ply, "ply\nformat ascii 1.0\nelement vertex 1e300\nproperty float x\nend_header\n");
  expectFileError([&] { dp::readPLY(ply); }, ply, "malformed element line");
  const std::string pts = dir.file("count.pts");
  writeText(pts, "1e300\n1 2 3\n");
  expectFileError([&] { dp::readTextPoints(pts); }, pts, "is not a count");
}

TEST(FuzzFindings, PcdHeaderNumbersOutOfRangeAreErrors)
{
  TempDir dir;
  const std::string path = dir.file("header.pcd");
  const std::pair<std::string, std::string> cases[] = {
      {"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 1.3e106\n", "bad SIZE entry '1.3e106'"},
      {"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 2.5\n", "bad COUNT entry"},
      {"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1e300\n", "bad WIDTH value"},
      {"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS inf\n", "bad POINTS value"},
      {"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1000000000000000\nHEIGHT "
       "1000000000000000\nDATA ascii\n",
       "too large"},
      {"VERSION 0.7\nFIELDS x y z rgb\nSIZE 8 4 4 2\nTYPE F F F U\nCOUNT 1 1 1 1\nPOINTS 1\n"
       "DATA ascii\n0 0 0 1\n",
       "a packed colour takes 4"},
  };
  expectEachRefused(path, cases, dp::readPCD);
}

TEST(FuzzFindings, PcdAsciiRgbThatIsNotAPackedColourIsAnError)
{
  // An ASCII rgb value beyond its type's range was cast (undefined; found by the campaign after
  // 7.7 M executions).
  TempDir dir;
  const std::string path = dir.file("rgb.pcd");
  const std::string head = "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nCOUNT 1 1 1 1\nPOINTS 1\n";
  const std::pair<std::string, std::string> cases[] = {
      {head + "TYPE F F F U\nDATA ascii\n0 0 0 4.4e80\n", "rgb value '4.4e80'"},
      {head + "TYPE F F F U\nDATA ascii\n0 0 0 -1\n", "is not a packed colour"},
      {head + "TYPE F F F I\nDATA ascii\n0 0 0 2.5\n", "is not a packed colour"},
      {head + "TYPE F F F F\nDATA ascii\n0 0 0 1e39\n", "is not a packed colour"},
  };
  expectEachRefused(path, cases, dp::readPCD);
}

TEST(FuzzFindings, ObjFaceIndexOutOfRangeIsAnError)
{
  TempDir dir;
  const std::string path = dir.file("face.obj");
  for (const char* index : {"1.8e94", "-1.8e94", "2.5", "nan", "4"})
  {
    writeText(path, std::string("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 ") + index + "\n");
    expectFileError([&] { dp::readOBJ(path); }, path, "face");
  }
  // A normal index out of range is ignored (the vertex keeps no normal), never cast.
  writeText(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1e300 2//1 3//1\n");
  EXPECT_EQ(dp::readOBJ(path).numberOfPoints(), 3u);
}

TEST(Reading, MissingFileAndDirectoryAreErrorsNamingThem)
{
  TempDir dir;
  expectFileError([&] { dp::readPointCloud(dir.file("absent.ply")); }, dir.file("absent.ply"),
                  "cannot open");
  std::filesystem::create_directory(dir.file("folder.ply"));
  expectFileError([&] { dp::readPointCloud(dir.file("folder.ply")); }, dir.file("folder.ply"), "");
  expectFileError([&] { dp::readPointCloud(dir.file("points.las")); }, dir.file("points.las"),
                  "unknown file extension");
}

TEST(Reading, NonFinitePointsAreDroppedAndCountedWithTheirAttributesAndFaces)
{
  TempDir dir;
  const std::string path = dir.file("nan.ply");
  dp::PointCloud cloud = sampleCloud(true);
  cloud.points[3] = std::numeric_limits<double>::quiet_NaN(); // point 1
  cloud.points[11] = std::numeric_limits<double>::infinity(); // point 3
  dp::writePLY(path, cloud, dp::PlyEncoding::BinaryBigEndian);
  dp::ReadReport report;
  const dp::PointCloud read = dp::readPointCloud(path, &report);
  EXPECT_EQ(report.droppedNonFinite, 2u);
  ASSERT_EQ(read.numberOfPoints(), 2u);
  EXPECT_EQ(read.attributes[0].values, (std::vector<float>{0.5f, 2.5f}));
  EXPECT_EQ(read.colors, (std::vector<std::uint8_t>{255, 0, 0, 0, 0, 255}));
  EXPECT_EQ(read.numberOfFaces(), 0u); // both faces used a dropped point
}

TEST(PCD, AsciiAndBinaryRoundTrip)
{
  TempDir dir;
  dp::PointCloud cloud = sampleCloud(false);
  cloud.attributes.clear();
  for (bool binary : {false, true})
  {
    const std::string path = dir.file(binary ? "b.pcd" : "a.pcd");
    dp::writePCD(path, cloud, binary);
    expectSameCloud(cloud, dp::readPCD(path));
  }
}

TEST(PCD, ReadsPclStyleHeaderWithPackedRgbCountsAndPadding)
{
  TempDir dir;
  const std::string path = dir.file("pcl.pcd");
  // rgb as an unsigned packed integer, a 2-component field and a padding field.
  writeText(path, "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
                  "FIELDS x y z rgb hist _\nSIZE 4 4 4 4 4 1\nTYPE F F F U F U\nCOUNT 1 1 1 1 2 1\n"
                  "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
                  "1 2 3 16711680 0.5 0.25 0\nnan nan nan 255 1 2 0\n");
  dp::ReadReport report;
  const dp::PointCloud c = dp::readPointCloud(path, &report);
  EXPECT_EQ(report.droppedNonFinite, 1u);
  ASSERT_EQ(c.numberOfPoints(), 1u);
  EXPECT_EQ(c.colors, (std::vector<std::uint8_t>{255, 0, 0}));
  ASSERT_EQ(c.attributes.size(), 1u);
  EXPECT_EQ(c.attributes[0].name, "hist");
  EXPECT_EQ(c.attributes[0].components, 2);
  EXPECT_EQ(c.attributes[0].values, (std::vector<float>{0.5f, 0.25f}));
}

TEST(PCD, ReadsBinaryCompressedFieldMajorWithLzfBackReferences)
{
  // PCL's layout: all x, then all y, z and rgb, LZF-compressed. The stream has literal runs and
  // one back-reference that copies 8 bytes from 4 back (overlapping: the colour repeated).
  const float xyz[9] = {0.0f, 0.5f, 1.0f, 0.1f, 0.2f, 0.3f, -1.0f, 0.0f, 1.0f};
  const std::uint32_t rgb = 0x00ff8040;
  std::string raw(reinterpret_cast<const char*>(xyz), sizeof xyz);
  const std::string colour(reinterpret_cast<const char*>(&rgb), 4);
  std::string lzf = std::string(1, '\x1f') + raw.substr(0, 32) + '\x03' + raw.substr(32, 4) +
                    '\x03' + colour + '\xc0' + '\x03';
  const std::uint32_t sizes[2] = {static_cast<std::uint32_t>(lzf.size()),
                                  static_cast<std::uint32_t>(raw.size() + 3 * colour.size())};
  TempDir dir;
  const std::string path = dir.file("compressed.pcd");
  writeText(path, "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
                  "WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA binary_compressed\n" +
                      std::string(reinterpret_cast<const char*>(sizes), 8) + lzf);
  const dp::PointCloud c = dp::readPCD(path);
  ASSERT_EQ(c.numberOfPoints(), 3u);
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t k = 0; k < 3; ++k)
      EXPECT_EQ(c.points[3 * i + k], static_cast<double>(xyz[3 * k + i])) << i << " " << k;
  EXPECT_EQ(c.colors, (std::vector<std::uint8_t>{255, 128, 64, 255, 128, 64, 255, 128, 64}));
}

TEST(PCD, TruncatedAndMalformedFilesAreErrors)
{
  TempDir dir;
  const std::string path = dir.file("cut.pcd");
  dp::writePCD(path, sampleCloud(false), true);
  const std::string whole = dp::test::readText(path);
  writeText(path, whole.substr(0, whole.size() - 5));
  expectFileError([&] { dp::readPCD(path); }, path, "truncated");
  writeText(path, "VERSION 0.7\nFIELDS x y z\nSIZE 4 4\n");
  expectFileError([&] { dp::readPCD(path); }, path, "SIZE has 2 entries");
  writeText(path, "VERSION 0.7\nFIELDS x y\nSIZE 4 4\nTYPE F F\nPOINTS 0\nDATA ascii\n");
  expectFileError([&] { dp::readPCD(path); }, path, "lacks one of the fields x, y, z");
  writeText(path, "VERSION 0.7\nFIELDS x y z\nPOINTS 1\nDATA binary_compressed\n\x05");
  expectFileError([&] { dp::readPCD(path); }, path, "binary_compressed");
}

TEST(Text, XyzWithNormalsCsvWithHeaderAndPtsWithCount)
{
  TempDir dir;
  writeText(dir.file("a.xyz"), "# comment\n0 0 0 0 0 1\n1 2 3 0 1 0\n");
  dp::PointCloud a = dp::readTextPoints(dir.file("a.xyz"));
  ASSERT_EQ(a.numberOfPoints(), 2u);
  EXPECT_EQ(a.normals[4], 1.0f);

  writeText(dir.file("b.csv"), "X,Y,Z,temperature\n1,2,3,20.5\n4,5,6,21.5\n");
  dp::PointCloud b = dp::readTextPoints(dir.file("b.csv"));
  ASSERT_EQ(b.numberOfPoints(), 2u);
  EXPECT_EQ(b.points[3], 4.0);
  ASSERT_EQ(b.attributes.size(), 1u);
  EXPECT_EQ(b.attributes[0].name, "temperature");

  writeText(dir.file("c.pts"), "2\n1 2 3 -500 10 20 30\n4 5 6 100 40 50 60\n");
  dp::PointCloud c = dp::readTextPoints(dir.file("c.pts"));
  ASSERT_EQ(c.numberOfPoints(), 2u);
  EXPECT_EQ(c.colors, (std::vector<std::uint8_t>{10, 20, 30, 40, 50, 60}));
  EXPECT_EQ(c.attributes[0].name, "Intensity");

  // Round trip through our writer, csv flavour included.
  dp::writeTextPoints(dir.file("d.csv"), a);
  expectSameCloud(a, dp::readTextPoints(dir.file("d.csv")));
}

TEST(Text, RaggedOrNonNumericLinesAreErrorsWithTheLineNumber)
{
  TempDir dir;
  const std::string path = dir.file("bad.xyz");
  writeText(path, "0 0 0\n1 1 1\n2 2\n");
  expectFileError([&] { dp::readTextPoints(path); }, path, "line 3 has 2 values");
  writeText(path, "0 0 0\n1 one 1\n");
  expectFileError([&] { dp::readTextPoints(path); }, path, "line 2");
  writeText(dir.file("short.pts"), "5\n1 2 3\n");
  expectFileError([&] { dp::readTextPoints(dir.file("short.pts")); }, dir.file("short.pts"),
                  "declares 5 points");
}

TEST(Text, EmptyFileGivesAnEmptyCloud)
{
  TempDir dir;
  writeText(dir.file("empty.xyz"), "# nothing here\n");
  EXPECT_EQ(dp::readTextPoints(dir.file("empty.xyz")).numberOfPoints(), 0u);
}

TEST(OBJ, ReadsVerticesNormalsThroughFacesAndNegativeIndices)
{
  TempDir dir;
  writeText(dir.file("m.obj"), "mtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0 1 0 0\nvn 0 0 1\n"
                               "vt 0 0\ng part\nf 1//1 2//1 -1//1\nf 1/1 2/1 3/1\n");
  const dp::PointCloud m = dp::readOBJ(dir.file("m.obj"));
  ASSERT_EQ(m.numberOfPoints(), 3u);
  EXPECT_EQ(m.numberOfFaces(), 2u);
  EXPECT_EQ(m.faceConnectivity, (std::vector<std::int64_t>{0, 1, 2, 0, 1, 2}));
  EXPECT_EQ(m.normals[2], 1.0f);
  EXPECT_TRUE(m.colors.empty()); // only one vertex had a colour

  dp::PointCloud cloud = sampleCloud(true);
  dp::writeOBJ(dir.file("r.obj"), cloud);
  expectSameCloud(cloud, dp::readOBJ(dir.file("r.obj")), false, false);
}

TEST(OBJ, BadFaceIndexIsAnError)
{
  TempDir dir;
  writeText(dir.file("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  expectFileError([&] { dp::readOBJ(dir.file("bad.obj")); }, dir.file("bad.obj"), "line 3");
}

TEST(Robustness, EveryTruncationIsAnErrorOrAShorterCloudNeverACrash)
{
  TempDir dir;
  dp::PointCloud cloud = sampleCloud(true);
  for (const char* name : {"t.ply", "t.pcd", "t.xyz", "t.csv", "t.obj"})
  {
    const std::string path = dir.file(name);
    dp::writePointCloud(path, cloud);
    const std::string whole = dp::test::readText(path);
    const bool binary = name == std::string("t.ply") || name == std::string("t.pcd");
    for (std::size_t cut = 0; cut < whole.size(); ++cut)
    {
      writeText(path, whole.substr(0, cut));
      try
      {
        const dp::PointCloud read = dp::readPointCloud(path);
        EXPECT_FALSE(binary) << name << " cut at " << cut << " read without an error";
        EXPECT_LE(read.numberOfPoints(), cloud.numberOfPoints());
        EXPECT_NO_THROW(read.validate());
      }
      catch (const dp::FileError& e)
      {
        EXPECT_EQ(std::string(e.what()).rfind(path, 0), 0u) << e.what();
      }
    }
  }
}

TEST(Robustness, AbsurdCountsInHeadersFailBeforeAllocating)
{
  TempDir dir;
  const std::string ply = dir.file("huge.ply");
  for (const char* format : {"ascii", "binary_little_endian"})
  {
    writeText(ply, std::string("ply\nformat ") + format +
                       " 1.0\nelement vertex 4000000000000\nproperty float x\nproperty float y\n"
                       "property float z\nend_header\n0 0 0\n");
    expectFileError([&] { dp::readPLY(ply); }, ply, "truncated");
  }
  writeText(ply, "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n"
                 "property float y\nproperty float z\nelement face 99999999999\n"
                 "property list uchar int vertex_indices\nend_header\n\x03");
  expectFileError([&] { dp::readPLY(ply); }, ply, "truncated");
  const std::string pcd = dir.file("huge.pcd");
  for (const char* data : {"ascii", "binary", "binary_compressed"})
  {
    writeText(pcd, std::string("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                               "WIDTH 1\nHEIGHT 1\nPOINTS 900000000000\nDATA ") +
                       data + "\n0 0 0\n");
    expectFileError([&] { dp::readPCD(pcd); }, pcd, "truncated");
  }
}

TEST(Formats, ExtensionsMapToFormats)
{
  EXPECT_EQ(dp::formatFromFileName("a/b.PLY"), dp::PointFileFormat::PLY);
  EXPECT_EQ(dp::formatFromFileName("x.pts"), dp::PointFileFormat::Text);
  EXPECT_EQ(dp::formatFromFileName("x.vtu"), dp::PointFileFormat::VTKXMLUnstructuredGrid);
  EXPECT_EQ(dp::formatFromFileName("dir.ply/noext"), dp::PointFileFormat::Unknown);
  EXPECT_FALSE(dp::isEngineFormat(dp::PointFileFormat::VTKLegacy));
}

} // namespace

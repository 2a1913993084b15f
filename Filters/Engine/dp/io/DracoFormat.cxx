// SPDX-License-Identifier: BSD-3-Clause
// Draco (.drc) reader and writer through Google's library (Debian's libdraco-dev): meshes and
// point clouds, as capture tools and game-engine players store takes frame by frame.
//
// Read: positions, normals and colours (8-bit, 16-bit or float channels to 0..255) of each
// point, and the mesh's triangles; other attributes (texture coordinates, generic) are skipped.
// Draco's decoder sizes its tables from counts inside the stream before it has read the data
// behind them (an edgebreaker mesh's face count can claim gigabytes in a few bytes), so those
// counts are parsed here first, held to what the file's size can code, and what the decoding
// will hold is asked of the memory budget (MemoryBudget.h) before the library allocates anything.
//
// Written: positions quantised to 14 bits of the bounding box (at most 2^-15 of its largest side
// off), normals to 10 bits, colours losslessly; triangles (edgebreaker) where the cloud has faces
// that are all triangles, else the points alone (kd-tree).
#include "dp/io/FileText.h"
#include "dp/io/MemoryBudget.h"
#include "dp/io/PointCloudIO.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/compression/point_cloud/point_cloud_decoder.h>
#include <draco/core/varint_decoding.h>
#include <draco/mesh/mesh.h>
#include <draco/metadata/metadata_decoder.h>

#include <algorithm>
#include <cmath>

namespace dp
{
namespace
{

// What Draco's decoder holds per count it reads (its corner table, traversal lists, quantised
// and decoded values of a position, a normal and a colour), with room to spare.
constexpr double DecoderBytesPerFace = 128;
constexpr double DecoderBytesPerPoint = 128;
// Draco sizes each attribute by its own declaration (up to 255 components of 8 bytes a point),
// read only after the connectivity, so the counts are also held to the file's size: no coding
// takes less than half a bit a point or a face (Draco's own take several bits), and a file
// declaring more is refused. With both, what a file makes the library allocate is bounded by a
// few kilobytes a byte of it, whatever its attributes declare.
constexpr double MostCountsPerByte = 16;
// What the decoded frame then takes as a PointCloud: positions, normals, RGBA, faces in CSR.
constexpr double CloudBytesPerPoint = 24 + 12 + 4;
constexpr double CloudBytesPerFace = 3 * 8 + 8;

struct DracoCounts
{
  bool mesh = false;
  double points = 0;
  double faces = 0;
};

[[noreturn]] void refuse(const std::string& path, const std::string& why)
{
  throw FileError(path, "not a readable Draco file: " + why);
}

// A Draco stream being read for its counts: the buffer past the header and its version.
struct CountReader
{
  const std::string& path;
  draco::DecoderBuffer buffer;
  int version = 0; // major * 256 + minor

  [[noreturn]] void cutShort() const { refuse(path, "it ends inside its counts (truncated)"); }
  // A count as the version codes it: 32 raw bits before 2.0, a varint since.
  std::uint32_t count()
  {
    std::uint32_t value = 0;
    if (!(version < 2 * 256 ? buffer.Decode(&value) : draco::DecodeVarint(&value, &buffer)))
      cutShort();
    return value;
  }
  template <typename T>
  T raw()
  {
    T value{};
    if (!buffer.Decode(&value))
      cutShort();
    return value;
  }
};

// A kd-tree point cloud before bitstream 2.3 declares its points a second time, inside its
// attribute data, and Draco sizes the attributes by that count: it is read here, past the
// attribute descriptors, and must be the header's. Draco's kd-tree encoder writes one attribute
// decoder; a stream with more would have the later ones' counts behind the first's data, so it is
// refused.
double oldKdTreePoints(CountReader& in)
{
  const auto decoders = in.raw<std::uint8_t>();
  if (decoders == 0)
    return 0;
  if (decoders > 1)
    refuse(in.path, "an old kd-tree point cloud with " + std::to_string(decoders) +
                        " attribute decoders (Draco's encoder writes one)");
  const std::uint32_t attributes = in.count();
  for (std::uint32_t a = 0; a < attributes; ++a)
  {
    in.raw<std::uint32_t>(); // type, data type, components, normalised: a byte each
    if (in.version < 1 * 256 + 3)
      in.raw<std::uint16_t>();
    else
      in.count();
  }
  in.raw<std::uint8_t>(); // method
  in.raw<std::uint8_t>(); // compression level
  return in.raw<std::uint32_t>();
}

DracoCounts pointCloudCounts(CountReader& in, std::uint8_t method)
{
  const auto declared = in.raw<std::int32_t>();
  DracoCounts counts;
  counts.points = declared < 0 ? 0 : declared;
  if (method == draco::POINT_CLOUD_KD_TREE_ENCODING && in.version < 2 * 256 + 3)
  {
    // Draco's encoder writes the same count twice; Draco decodes the attributes by the second.
    const double again = oldKdTreePoints(in);
    if (again != counts.points)
      refuse(in.path, "its two point counts differ (" +
                          std::to_string(static_cast<std::uint64_t>(counts.points)) + " and " +
                          std::to_string(static_cast<std::uint64_t>(again)) + ")");
  }
  return counts;
}

DracoCounts meshCounts(CountReader& in, std::uint8_t method)
{
  DracoCounts counts;
  counts.mesh = true;
  if (method == draco::MESH_SEQUENTIAL_ENCODING)
  {
    // Counts of 32 raw bits before 2.2, varints since.
    const bool raw = in.version < 2 * 256 + 2;
    counts.faces = raw ? in.raw<std::uint32_t>() : in.count();
    counts.points = raw ? in.raw<std::uint32_t>() : in.count();
  }
  else if (method == draco::MESH_EDGEBREAKER_ENCODING)
  {
    in.raw<std::uint8_t>(); // traversal
    if (in.version < 2 * 256 + 2)
      in.count(); // new vertices
    counts.points = in.count();
    counts.faces = in.count();
  }
  else
    refuse(in.path, "mesh method " + std::to_string(method) + " is not Draco's");
  return counts;
}

// The counts a Draco stream declares before its data: the header, the metadata, then the
// method's own counts (Draco's bitstreams up to 2.2 for meshes, 2.3 for point clouds).
DracoCounts readDeclaredCounts(const std::string& path, std::string_view bytes)
{
  CountReader in{path, {}, 0};
  in.buffer.Init(bytes.data(), bytes.size());
  draco::DracoHeader header;
  if (!draco::PointCloudDecoder::DecodeHeader(&in.buffer, &header).ok())
    refuse(path, "no Draco header (the file does not start with 'DRACO', or ends inside it)");
  in.version = header.version_major * 256 + header.version_minor;
  const bool pointCloud = header.encoder_type == draco::POINT_CLOUD;
  if (header.version_major < 1 || in.version > 2 * 256 + (pointCloud ? 3 : 2))
    refuse(path, "bitstream version " + std::to_string(header.version_major) + "." +
                     std::to_string(header.version_minor) + " (this build reads 1.0 to " +
                     (pointCloud ? "2.3" : "2.2") + ")");
  in.buffer.set_bitstream_version(
      DRACO_BITSTREAM_VERSION(header.version_major, header.version_minor));
  if (in.version >= 1 * 256 + 3 && (header.flags & METADATA_FLAG_MASK))
  {
    draco::GeometryMetadata metadata;
    if (!draco::MetadataDecoder().DecodeGeometryMetadata(&in.buffer, &metadata))
      refuse(path, "its metadata are corrupt or cut short");
  }
  if (pointCloud)
    return pointCloudCounts(in, header.encoder_method);
  if (header.encoder_type != draco::TRIANGULAR_MESH)
    refuse(path, "geometry type " + std::to_string(header.encoder_type) +
                     " is neither a point cloud nor a mesh");
  return meshCounts(in, header.encoder_method);
}

// A colour channel as 0..255: floats and normalised integers come as 0..1 (Draco's conversion),
// other 16-bit channels as 0..65535.
std::uint8_t toByte(float value, const draco::PointAttribute& colour)
{
  const draco::DataType type = colour.data_type();
  if (colour.normalized() || type == draco::DT_FLOAT32 || type == draco::DT_FLOAT64)
    value *= 255.0f;
  else if (type == draco::DT_UINT16)
    value /= 257.0f;
  return static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
}

// Numbers Draco's conversion can read: not its booleans (a byte other than 0 or 1 is no bool),
// not an invalid type.
bool numeric(const draco::PointAttribute& attribute)
{
  const draco::DataType type = attribute.data_type();
  return type != draco::DT_BOOL && type != draco::DT_INVALID && type < draco::DT_TYPES_COUNT;
}

// Whether every point's value lies inside the attribute's decoded values (a corrupt stream can
// leave an attribute with fewer values than points).
bool holdsEveryPoint(const draco::PointAttribute& attribute, std::size_t points)
{
  if (points > 0 && (attribute.size() == 0 || attribute.buffer() == nullptr))
    return false;
  for (std::size_t i = 0; i < points; ++i)
    if (attribute.mapped_index(draco::PointIndex(static_cast<std::uint32_t>(i))).value() >=
        attribute.size())
      return false;
  return true;
}

// An attribute that can be read for every point: present, numeric, holding every point.
bool readable(const draco::PointAttribute* attribute, std::size_t points)
{
  return attribute && numeric(*attribute) && holdsEveryPoint(*attribute, points);
}

void copyAttributes(const draco::PointCloud& source, PointCloud& cloud)
{
  const std::size_t n = source.num_points();
  const draco::PointAttribute* position =
      source.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (!readable(position, n) || position->num_components() < 3)
    throw std::runtime_error("it has no positions of 3 numbers for each of its points");
  cloud.points.resize(3 * n);
  float value[4] = {0, 0, 0, 0};
  for (std::size_t i = 0; i < n; ++i)
  {
    position->ConvertValue<float>(position->mapped_index(draco::PointIndex(i)), 3, value);
    std::copy(value, value + 3, cloud.points.begin() + 3 * i);
  }
  const draco::PointAttribute* normal = source.GetNamedAttribute(draco::GeometryAttribute::NORMAL);
  if (readable(normal, n) && normal->num_components() == 3)
  {
    cloud.normals.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i)
      normal->ConvertValue<float>(normal->mapped_index(draco::PointIndex(i)), 3,
                                  cloud.normals.data() + 3 * i);
  }
  const draco::PointAttribute* colour = source.GetNamedAttribute(draco::GeometryAttribute::COLOR);
  if (readable(colour, n) && (colour->num_components() == 3 || colour->num_components() == 4))
  {
    const int channels = colour->num_components();
    cloud.colorComponents = channels;
    cloud.colors.resize(channels * n);
    for (std::size_t i = 0; i < n; ++i)
    {
      colour->ConvertValue<float>(colour->mapped_index(draco::PointIndex(i)), channels, value);
      for (int c = 0; c < channels; ++c)
        cloud.colors[channels * i + c] = toByte(value[c], *colour);
    }
  }
}

// Refuses counts more than any coding of `size` bytes holds, then claims from the memory budget
// what Draco's decoder and the decoded frame hold.
void claimDecoding(const std::string& path, std::size_t size, const DracoCounts& counts)
{
  const double most = MostCountsPerByte * static_cast<double>(size);
  if (counts.points > most || counts.faces > most)
    refuse(path, "it declares " + std::to_string(static_cast<std::uint64_t>(counts.points)) +
                     " points and " + std::to_string(static_cast<std::uint64_t>(counts.faces)) +
                     " faces in " + std::to_string(size) +
                     " bytes, more than any coding holds (corrupt)");
  MemoryAccount account(path);
  account.claim(counts.points * DecoderBytesPerPoint + counts.faces * DecoderBytesPerFace,
                "Draco's decoder for " + std::to_string(static_cast<std::uint64_t>(counts.points)) +
                    " points and " + std::to_string(static_cast<std::uint64_t>(counts.faces)) +
                    " faces");
  account.claim(counts.points * CloudBytesPerPoint + counts.faces * CloudBytesPerFace,
                "the decoded frame");
}

// What Draco decodes of a file: its points, and the same as a mesh where the file holds one.
struct DracoGeometry
{
  std::unique_ptr<draco::PointCloud> geometry;
  const draco::Mesh* mesh = nullptr;
};

// The file's geometry as Draco decodes it: a mesh where `mesh`, else a point cloud.
DracoGeometry decodeGeometry(const std::string& path, const std::string& bytes, bool mesh)
{
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::Decoder decoder;
  DracoGeometry out;
  if (mesh)
  {
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok())
      refuse(path, decoded.status().error_msg_string() + " (corrupt or truncated)");
    out.mesh = decoded.value().get();
    out.geometry = std::move(decoded).value();
  }
  else
  {
    auto decoded = decoder.DecodePointCloudFromBuffer(&buffer);
    if (!decoded.ok())
      refuse(path, decoded.status().error_msg_string() + " (corrupt or truncated)");
    out.geometry = std::move(decoded).value();
  }
  return out;
}

// The mesh's triangles as the cloud's faces.
void copyTriangles(const draco::Mesh& mesh, PointCloud& cloud)
{
  cloud.faceOffsets.reserve(mesh.num_faces() + 1);
  cloud.faceConnectivity.reserve(3 * std::size_t{mesh.num_faces()});
  for (draco::FaceIndex f(0); f < mesh.num_faces(); ++f)
  {
    const draco::Mesh::Face& face = mesh.face(f);
    const std::int64_t ids[3] = {face[0].value(), face[1].value(), face[2].value()};
    cloud.addFace(ids, 3);
  }
}

} // namespace

PointCloud readDRC(const std::string& path)
{
  const std::string bytes = support::readWholeFile(path);
  const DracoCounts counts = readDeclaredCounts(path, bytes);
  claimDecoding(path, bytes.size(), counts);
  const DracoGeometry decoded = decodeGeometry(path, bytes, counts.mesh);
  PointCloud cloud;
  try
  {
    copyAttributes(*decoded.geometry, cloud);
  }
  catch (const std::runtime_error& e)
  {
    refuse(path, e.what());
  }
  if (decoded.mesh)
    copyTriangles(*decoded.mesh, cloud);
  return cloud;
}

namespace
{

// A Draco attribute of `components` values per point, filled from `values` (one per point).
template <typename T>
void addAttribute(draco::PointCloud& target, draco::GeometryAttribute::Type type, int components,
                  draco::DataType dataType, bool normalised, const T* values)
{
  draco::GeometryAttribute attribute;
  attribute.Init(type, nullptr, components, dataType, normalised, sizeof(T) * components, 0);
  const int id = target.AddAttribute(attribute, true, target.num_points());
  draco::PointAttribute* stored = target.attribute(id);
  for (draco::PointIndex i(0); i < target.num_points(); ++i)
    stored->SetAttributeValue(draco::AttributeValueIndex(i.value()),
                              values + components * i.value());
}

bool allTriangles(const PointCloud& cloud)
{
  for (std::size_t f = 0; f < cloud.numberOfFaces(); ++f)
    if (cloud.faceOffsets[f + 1] - cloud.faceOffsets[f] != 3)
      return false;
  return cloud.numberOfFaces() > 0;
}

} // namespace

void writeDRC(const std::string& path, const PointCloud& cloud)
{
  const bool mesh = allTriangles(cloud);
  std::unique_ptr<draco::PointCloud> target =
      mesh ? std::make_unique<draco::Mesh>() : std::make_unique<draco::PointCloud>();
  target->set_num_points(static_cast<std::uint32_t>(cloud.numberOfPoints()));
  const std::vector<float> positions(cloud.points.begin(), cloud.points.end());
  addAttribute(*target, draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32, false,
               positions.data());
  if (cloud.hasNormals())
    addAttribute(*target, draco::GeometryAttribute::NORMAL, 3, draco::DT_FLOAT32, false,
                 cloud.normals.data());
  if (cloud.hasColors())
    addAttribute(*target, draco::GeometryAttribute::COLOR, cloud.colorComponents, draco::DT_UINT8,
                 true, cloud.colors.data());
  if (mesh)
  {
    auto* triangles = static_cast<draco::Mesh*>(target.get());
    for (std::size_t f = 0; f < cloud.numberOfFaces(); ++f)
    {
      const std::int64_t* ids = cloud.faceConnectivity.data() + cloud.faceOffsets[f];
      triangles->AddFace({draco::PointIndex(static_cast<std::uint32_t>(ids[0])),
                          draco::PointIndex(static_cast<std::uint32_t>(ids[1])),
                          draco::PointIndex(static_cast<std::uint32_t>(ids[2]))});
    }
  }
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, 14);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, 10);
  draco::EncoderBuffer out;
  const draco::Status status =
      mesh ? encoder.EncodeMeshToBuffer(*static_cast<draco::Mesh*>(target.get()), &out)
           : encoder.EncodePointCloudToBuffer(*target, &out);
  if (!status.ok())
    throw FileError(path, "Draco cannot encode it: " + status.error_msg_string());
  support::writeBesideAndMove(
      path, [&](const std::string& partial)
      { support::writeWholeFile(partial, std::string(out.data(), out.size())); });
}

} // namespace dp

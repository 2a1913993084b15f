// SPDX-License-Identifier: BSD-3-Clause
#include "dp/export/GltfExport.h"
#include "dp/compress/DetailCoding.h"
#include "dp/geometry/SubdivisionMap.h"
#include "dp/io/FileText.h"

#include <meshoptimizer.h>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace dp
{
namespace
{

constexpr double FramesPerSecond = 24.0;

// Appends `size` bytes to buffer 0 (4-byte aligned) and a view of them (`target`, `stride`: 0
// for none); returns the view.
int addView(tinygltf::Model& model, const unsigned char* bytes, std::size_t size, int target,
            std::size_t stride)
{
  auto& data = model.buffers[0].data;
  data.resize((data.size() + 3) & ~std::size_t{3});
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = data.size();
  view.byteLength = size;
  view.byteStride = stride;
  if (target)
    view.target = target;
  data.insert(data.end(), bytes, bytes + size);
  model.bufferViews.push_back(view);
  return static_cast<int>(model.bufferViews.size()) - 1;
}

// Appends `values` to the buffer and adds a view and an accessor for them.
int addAccessor(tinygltf::Model& model, const std::vector<float>& values, int type,
                std::size_t count, bool withBounds, int target)
{
  tinygltf::Accessor accessor;
  accessor.bufferView = addView(model, reinterpret_cast<const unsigned char*>(values.data()),
                                values.size() * sizeof(float), target, 0);
  accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  accessor.count = count;
  accessor.type = type;
  if (withBounds)
  {
    const std::size_t width = values.size() / std::max<std::size_t>(count, 1);
    accessor.minValues.assign(width, std::numeric_limits<double>::infinity());
    accessor.maxValues.assign(width, -std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < values.size(); ++i)
    {
      accessor.minValues[i % width] = std::min<double>(accessor.minValues[i % width], values[i]);
      accessor.maxValues[i % width] = std::max<double>(accessor.maxValues[i % width], values[i]);
    }
  }
  model.accessors.push_back(accessor);
  return static_cast<int>(model.accessors.size()) - 1;
}

// Appends `bytes` (elements of `stride` bytes, each a multiple of 4 as glTF wants of vertex
// attributes) as a vertex-attribute view and adds an accessor of `count` elements of `type` in
// `componentType` over it; returns the accessor.
int addAttributeBytes(tinygltf::Model& model, const std::vector<unsigned char>& bytes,
                      int componentType, int type, std::size_t count, std::size_t stride,
                      bool normalized)
{
  tinygltf::Accessor accessor;
  accessor.bufferView =
      addView(model, bytes.data(), bytes.size(), TINYGLTF_TARGET_ARRAY_BUFFER, stride);
  accessor.componentType = componentType;
  accessor.normalized = normalized;
  accessor.count = count;
  accessor.type = type;
  model.accessors.push_back(accessor);
  return static_cast<int>(model.accessors.size()) - 1;
}

// Compresses every buffer view of `model` (all in buffer 0) with meshoptimizer and returns the
// EXT_meshopt_compression object of each view; buffer 0 then holds the compressed bytes. The
// views keep their offsets into the original bytes, which become the fallback buffer 1.
std::vector<nlohmann::json> compressViews(tinygltf::Model& model, std::size_t vertices,
                                          std::size_t& fallbackBytes)
{
  const std::vector<unsigned char> raw = model.buffers[0].data;
  fallbackBytes = raw.size();
  std::vector<unsigned char>& packed = model.buffers[0].data;
  packed.clear();
  std::vector<nlohmann::json> extensions(model.bufferViews.size());
  for (const tinygltf::Accessor& a : model.accessors)
  {
    const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(a.bufferView)];
    const unsigned char* source = raw.data() + view.byteOffset;
    const bool indices = view.target == TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
    const std::size_t stride = indices           ? 4
                               : view.byteStride ? view.byteStride
                                                 : 4 * (a.type == TINYGLTF_TYPE_VEC3 ? 3 : 1);
    std::vector<unsigned char> out;
    if (indices)
    {
      out.resize(meshopt_encodeIndexBufferBound(a.count, vertices));
      out.resize(meshopt_encodeIndexBuffer(out.data(), out.size(),
                                           reinterpret_cast<const unsigned int*>(source), a.count));
    }
    else
    {
      out.resize(meshopt_encodeVertexBufferBound(a.count, stride));
      out.resize(meshopt_encodeVertexBuffer(out.data(), out.size(), source, a.count, stride));
    }
    if (out.empty())
      throw std::runtime_error("meshoptimizer could not encode a buffer view");
    packed.resize((packed.size() + 3) & ~std::size_t{3});
    extensions[static_cast<std::size_t>(a.bufferView)] = {
        {"buffer", 0},
        {"byteOffset", packed.size()},
        {"byteLength", out.size()},
        {"byteStride", stride},
        {"count", a.count},
        {"mode", indices ? "TRIANGLES" : "ATTRIBUTES"}};
    packed.insert(packed.end(), out.begin(), out.end());
  }
  packed.resize((packed.size() + 3) & ~std::size_t{3});
  return extensions;
}

// A GLB file's bytes with its JSON chunk replaced.
std::string withJson(const std::string& glb, const nlohmann::json& json)
{
  std::string text = json.dump();
  text.resize((text.size() + 3) & ~std::size_t{3}, ' ');
  std::uint32_t jsonLength = 0;
  std::memcpy(&jsonLength, glb.data() + 12, 4);
  const std::string rest = glb.substr(20 + jsonLength); // the BIN chunk
  std::string out(12, '\0');
  const std::uint32_t chunkLength = static_cast<std::uint32_t>(text.size());
  out.append(reinterpret_cast<const char*>(&chunkLength), 4);
  out.append("JSON", 4);
  out += text;
  out += rest;
  const std::uint32_t magic = 0x46546C67, version = 2,
                      total = static_cast<std::uint32_t>(out.size());
  std::memcpy(out.data(), &magic, 4);
  std::memcpy(out.data() + 4, &version, 4);
  std::memcpy(out.data() + 8, &total, 4);
  return out;
}

// The shape model with each weight track rescaled into [0, 1] (glTF players expect morph
// weights there) and its offset folded into the base shape.
struct MorphTargets
{
  Eigen::VectorXd base;    // 3Nv
  Eigen::MatrixXd targets; // 3Nv x k
  Eigen::MatrixXd weights; // Nt x k
};

MorphTargets morphTargetsOf(const PcaModel& m)
{
  MorphTargets out{m.mean, m.basis, m.weights};
  for (std::size_t j = 0; j < m.components(); ++j)
  {
    const double lo = out.weights.col(j).minCoeff(), hi = out.weights.col(j).maxCoeff();
    out.base += lo * m.basis.col(j);
    if (hi > lo)
    {
      out.targets.col(j) *= hi - lo;
      out.weights.col(j) = (out.weights.col(j).array() - lo) / (hi - lo);
    }
    else
    {
      out.targets.col(j).setZero();
      out.weights.col(j).setZero();
    }
  }
  return out;
}

// The triangles as 32-bit indices; returns their accessor.
int addIndices(tinygltf::Model& model, const std::vector<std::int64_t>& triangles)
{
  auto& data = model.buffers[0].data;
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = data.size();
  view.byteLength = triangles.size() * sizeof(std::uint32_t);
  view.target = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
  for (std::int64_t index : triangles)
  {
    const auto v = static_cast<std::uint32_t>(index);
    const auto* b = reinterpret_cast<const unsigned char*>(&v);
    data.insert(data.end(), b, b + 4);
  }
  model.bufferViews.push_back(view);
  tinygltf::Accessor indices;
  indices.bufferView = static_cast<int>(model.bufferViews.size()) - 1;
  indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
  indices.count = triangles.size();
  indices.type = TINYGLTF_TYPE_SCALAR;
  model.accessors.push_back(indices);
  return static_cast<int>(model.accessors.size()) - 1;
}

// Colour differences are stored as normalized signed shorts: exact to 1/65534, so each frame's
// bytes come back at its key, in 8 bytes a vertex (x y z and the padding glTF asks for).
constexpr double ShortScale = 32767.0;

// Names the morph targets (extras.targetNames, which Blender and three.js show): "shape j" for
// the shape components, "colour of frame t" for the colour targets, so that the shape keys that
// only change colour are told apart from those that move the mesh.
void nameTargets(tinygltf::Mesh& mesh, std::size_t shapes, std::size_t colourTargets)
{
  tinygltf::Value::Array names;
  for (std::size_t j = 0; j < shapes; ++j)
    names.emplace_back("shape " + std::to_string(j));
  for (std::size_t t = 1; t <= colourTargets; ++t)
    names.emplace_back("colour of frame " + std::to_string(t));
  tinygltf::Value::Object extras;
  extras["targetNames"] = tinygltf::Value(std::move(names));
  mesh.extras = tinygltf::Value(std::move(extras));
}

// Frame 0's colours as the base's COLOR_0 (normalized bytes, padded to 4 per vertex) and, for
// each later frame, a morph target holding its colours' change from frame 0. glTF morphs all
// attributes of a target by one weight, so colour that changes on its own cannot ride on the
// shape targets: each frame's colour target is weighted 1 at its key and 0 elsewhere (see
// colourWeights), and LINEAR interpolation blends neighbouring frames' colours. Every target
// gets both attributes, the ones it does not change as a shared accessor of zeros: players that
// fill a missing target attribute with the base's (three.js) would otherwise add the base to it.
// Returns the number of colour targets added.
std::size_t addColourTargets(tinygltf::Model& model, tinygltf::Primitive& primitive,
                             tinygltf::Mesh& mesh, const std::vector<std::uint8_t>& colours,
                             std::size_t nv, std::size_t nt)
{
  std::vector<unsigned char> base(4 * nv, 0);
  for (std::size_t v = 0; v < nv; ++v)
    std::copy_n(colours.begin() + static_cast<std::ptrdiff_t>(3 * v), 3, base.begin() + 4 * v);
  primitive.attributes["COLOR_0"] = addAttributeBytes(
      model, base, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_VEC3, nv, 4, true);
  if (nt < 2)
    return 0;
  const int noColourChange =
      addAttributeBytes(model, std::vector<unsigned char>(8 * nv, 0), TINYGLTF_COMPONENT_TYPE_SHORT,
                        TINYGLTF_TYPE_VEC3, nv, 8, true);
  for (auto& target : primitive.targets)
    target["COLOR_0"] = noColourChange;
  const int noMotion = addAccessor(model, std::vector<float>(3 * nv, 0.0f), TINYGLTF_TYPE_VEC3, nv,
                                   true, TINYGLTF_TARGET_ARRAY_BUFFER);
  for (std::size_t t = 1; t < nt; ++t)
  {
    std::vector<unsigned char> change(8 * nv, 0);
    for (std::size_t v = 0; v < nv; ++v)
      for (std::size_t c = 0; c < 3; ++c)
      {
        const int d = colours[3 * (nv * t + v) + c] - colours[3 * v + c];
        const auto q = static_cast<std::int16_t>(std::lround(d * ShortScale / 255.0));
        std::memcpy(change.data() + 8 * v + 2 * c, &q, 2);
      }
    primitive.targets.push_back(
        {{"POSITION", noMotion},
         {"COLOR_0", addAttributeBytes(model, change, TINYGLTF_COMPONENT_TYPE_SHORT,
                                       TINYGLTF_TYPE_VEC3, nv, 8, true)}});
    mesh.weights.push_back(0.0);
  }
  nameTargets(mesh, primitive.targets.size() - (nt - 1), nt - 1);
  return nt - 1;
}

// The shape weights with a colour target per frame after the first beside them: frame t's
// weighted 1 at key t, every other 0.
Eigen::MatrixXd colourWeights(const Eigen::MatrixXd& shapes, std::size_t colourTargets)
{
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(shapes.rows(), shapes.cols() + colourTargets);
  w.leftCols(shapes.cols()) = shapes;
  for (std::size_t t = 1; t <= colourTargets; ++t)
    w(static_cast<Eigen::Index>(t), shapes.cols() + static_cast<Eigen::Index>(t) - 1) = 1;
  return w;
}

// One node with the mesh: the base shape, the triangles and a morph target per component; with
// colour, COLOR_0 and a colour target per frame after the first (addColourTargets). Returns the
// number of colour targets.
std::size_t addMesh(tinygltf::Model& model, const MorphTargets& morph,
                    const CompressedSequence& sequence)
{
  const std::size_t nv = sequence.pca.model.vertices;
  const std::vector<std::int64_t>& triangles = sequence.triangles;
  std::vector<float> positions(morph.base.data(), morph.base.data() + morph.base.size());
  tinygltf::Primitive primitive;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  primitive.attributes["POSITION"] =
      addAccessor(model, positions, TINYGLTF_TYPE_VEC3, nv, true, TINYGLTF_TARGET_ARRAY_BUFFER);
  primitive.indices = addIndices(model, triangles);
  tinygltf::Mesh mesh;
  mesh.name = "tracked";
  for (Eigen::Index j = 0; j < morph.targets.cols(); ++j)
  {
    std::vector<float> target(morph.targets.col(j).data(), morph.targets.col(j).data() + 3 * nv);
    primitive.targets.push_back({{"POSITION", addAccessor(model, target, TINYGLTF_TYPE_VEC3, nv,
                                                          true, TINYGLTF_TARGET_ARRAY_BUFFER)}});
    mesh.weights.push_back(morph.weights(0, j));
  }
  const std::size_t colourTargets = sequence.colours.empty()
                                        ? 0
                                        : addColourTargets(model, primitive, mesh, sequence.colours,
                                                           nv, sequence.pca.model.frames);
  mesh.primitives.push_back(primitive);
  model.meshes.push_back(mesh);
  tinygltf::Node node;
  node.mesh = 0;
  node.name = "tracked";
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes.push_back(0);
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  return colourTargets;
}

// The weights over time: one linear sampler, a key per frame at FramesPerSecond.
void addAnimation(tinygltf::Model& model, const Eigen::MatrixXd& weights)
{
  const std::size_t nt = static_cast<std::size_t>(weights.rows()),
                    k = static_cast<std::size_t>(weights.cols());
  std::vector<float> times(nt), values(nt * k);
  for (std::size_t t = 0; t < nt; ++t)
  {
    // The float at or just below t/24: players that step at 1/24 s from 0 (VTK's glTF reader)
    // then meet the last key exactly once instead of a rounding step after it.
    const double seconds = static_cast<double>(t) / FramesPerSecond;
    times[t] = static_cast<float>(seconds);
    if (static_cast<double>(times[t]) > seconds)
      times[t] = std::nextafter(times[t], 0.0f);
    for (std::size_t j = 0; j < k; ++j)
      values[t * k + j] =
          static_cast<float>(weights(static_cast<Eigen::Index>(t), static_cast<Eigen::Index>(j)));
  }
  tinygltf::AnimationSampler sampler;
  sampler.input = addAccessor(model, times, TINYGLTF_TYPE_SCALAR, nt, true, 0);
  sampler.output = addAccessor(model, values, TINYGLTF_TYPE_SCALAR, nt * k, false, 0);
  sampler.interpolation = "LINEAR";
  tinygltf::AnimationChannel channel;
  channel.sampler = 0;
  channel.target_node = 0;
  channel.target_path = "weights";
  tinygltf::Animation animation;
  animation.name = "sequence";
  animation.samplers.push_back(sampler);
  animation.channels.push_back(channel);
  model.animations.push_back(animation);
}

// The .glb with every buffer view compressed by meshoptimizer (EXT_meshopt_compression).
// tinygltf writes buffer 0 (now the compressed bytes) as the BIN chunk; the views' extensions
// and the fallback buffer are added to its JSON.
void writeMeshoptGlb(const std::string& file, const std::string& path, tinygltf::Model& model,
                     std::size_t nv)
{
  tinygltf::TinyGLTF writer;
  std::size_t fallbackBytes = 0;
  const std::vector<nlohmann::json> views = compressViews(model, nv, fallbackBytes);
  std::ostringstream stream;
  if (!writer.WriteGltfSceneToStream(&model, stream, false, true))
    throw std::runtime_error(path + ": cannot write the glTF file");
  const std::string glb = stream.str();
  std::uint32_t jsonLength = 0;
  std::memcpy(&jsonLength, glb.data() + 12, 4);
  nlohmann::json json = nlohmann::json::parse(glb.substr(20, jsonLength));
  for (std::size_t v = 0; v < views.size(); ++v)
  {
    json["bufferViews"][v]["buffer"] = 1;
    json["bufferViews"][v]["extensions"]["EXT_meshopt_compression"] = views[v];
  }
  json["buffers"][1] = {{"byteLength", fallbackBytes},
                        {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}};
  json["extensionsUsed"] = {"EXT_meshopt_compression"};
  json["extensionsRequired"] = {"EXT_meshopt_compression"};
  const std::string bytes = withJson(glb, json);
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out)
    throw std::runtime_error(path + ": cannot write the glTF file");
}

} // namespace

namespace
{
// Level `level` of a sequence's detail layer as a sequence of its own: that level's vertices of
// the decoded fine mesh on that level's triangles, decomposed again into shapes within the
// layer's coding error, with their colours.
CompressedSequence detailLevelSequence(const CompressedSequence& s, int level)
{
  const std::size_t nb = s.pca.model.vertices, frames = s.pca.model.frames;
  const SubdivisionMap fine(s.triangles, nb, s.detail.levels), at(s.triangles, nb, level);
  const std::size_t n = at.fineVertices();
  std::vector<double> positions(3 * n * frames), all(3 * fine.fineVertices());
  for (std::size_t t = 0; t < frames; ++t)
  {
    detailedFrame(s, fine, t, all.data());
    std::copy(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(3 * n),
              positions.begin() + static_cast<std::ptrdiff_t>(3 * n * t));
  }
  PcaOptions o;
  o.layout = PcaLayout::Shapes;
  o.measure = PcaErrorMeasure::RmsDeviation;
  o.target = std::max({s.detail.step / std::sqrt(12.0), s.report.rmsError, 1e-9});
  o.quantise = false;
  CompressedSequence out =
      compressSequence(positions.data(), n, frames, o, at.fineTriangles(), s.times);
  for (std::size_t t = 0; t < frames && !s.colours.empty(); ++t)
  {
    const std::vector<std::uint8_t> c = subdividedColours(fine, s.colours.data() + 3 * nb * t);
    out.colours.insert(out.colours.end(), c.begin(),
                       c.begin() + static_cast<std::ptrdiff_t>(3 * n));
  }
  return out;
}

// A sequence of the trajectory layout as morph targets need it: its decoded frames decomposed
// again as shapes (float, as the .glb stores them), within a quarter of its own coding error (a
// millionth of its size when that is not known), which adds 3 % to that error.
CompressedSequence asShapes(const CompressedSequence& s)
{
  const PcaModel& m = s.pca.model;
  const std::size_t values = 3 * m.vertices;
  std::vector<double> positions(values * m.frames);
  for (std::size_t t = 0; t < m.frames; ++t)
    m.frame(t, positions.data() + values * t);
  PcaOptions o;
  o.layout = PcaLayout::Shapes;
  o.measure = PcaErrorMeasure::RmsDeviation;
  o.quantise = false;
  const auto [lo, hi] = std::minmax_element(positions.begin(), positions.end());
  o.target = s.report.rmsError > 0 ? 0.25 * s.report.rmsError : 1e-6 * std::max(*hi - *lo, 1e-9);
  CompressedSequence out =
      compressSequence(positions.data(), m.vertices, m.frames, o, s.triangles, s.times);
  out.colours = s.colours;
  return out;
}

// About what writeGlb stores for `s`: float positions and targets, weights, indices, colour.
double glbBytes(const CompressedSequence& s)
{
  const auto n = static_cast<double>(s.pca.model.vertices);
  const auto k = static_cast<double>(s.pca.model.components());
  const auto frames = static_cast<double>(s.pca.model.frames);
  const double colour = s.colours.empty() ? 0.0 : 4 * n + 8 * n * (frames - 1);
  return 12 * n * (k + 1) + 4 * k * frames + 4 * static_cast<double>(s.triangles.size()) + colour;
}
} // namespace

GlbLevel glbLevelOf(const CompressedSequence& sequence, const GlbOptions& options)
{
  GlbLevel out;
  const int levels = sequence.detail.levels;
  if (levels == 0 || options.detailLevel == 0)
    return out;
  const bool automatic = options.detailLevel < 0;
  for (int level = automatic ? levels : std::min(options.detailLevel, levels); level >= 1; --level)
  {
    CompressedSequence written = detailLevelSequence(sequence, level);
    if (!automatic || glbBytes(written) <= static_cast<double>(options.maximumBytes))
    {
      out.level = level;
      out.written = std::move(written);
      return out;
    }
  }
  return out;
}

GlbSummary writeGlb(const std::string& path, const CompressedSequence& given,
                    const GlbOptions& options)
{
  const GlbLevel level = glbLevelOf(given, options);
  std::optional<CompressedSequence> shapes;
  if (!level.written && given.pca.model.layout != PcaLayout::Shapes)
    shapes = asShapes(given);
  const CompressedSequence& sequence = level.written ? *level.written : shapes ? *shapes : given;
  const PcaModel& m = sequence.pca.model;
  if (sequence.triangles.empty())
    throw std::invalid_argument("glTF export needs triangles");
  if (!sequence.colours.empty() && sequence.colours.size() != 3 * m.vertices * m.frames)
    throw std::invalid_argument("glTF export: " + std::to_string(sequence.colours.size()) +
                                " colour bytes for " + std::to_string(m.frames) + " frames of " +
                                std::to_string(m.vertices) + " vertices (3 each)");
  const MorphTargets morph = morphTargetsOf(m);
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "DynamicPoints";
  model.buffers.resize(1);
  const std::size_t colourTargets = addMesh(model, morph, sequence);
  if (m.components() + colourTargets > 0 && m.frames > 1)
    addAnimation(model, colourWeights(morph.weights, colourTargets));

  // Written beside and renamed, so a failed write never leaves a broken file under the name.
  support::writeBesideAndMove(path,
                              [&](const std::string& partial)
                              {
                                if (options.meshopt)
                                  writeMeshoptGlb(partial, path, model, m.vertices);
                                else if (!tinygltf::TinyGLTF().WriteGltfSceneToFile(
                                             &model, partial, true, true, false, true))
                                  throw std::runtime_error(path + ": cannot write the glTF file");
                              });
  return {level.level, m.vertices, m.components()};
}

} // namespace dp

// SPDX-License-Identifier: BSD-3-Clause
#include "dp/export/GltfExport.h"
#include "dp/detail/FileText.h"

#include <meshoptimizer.h>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace dp
{
namespace
{

constexpr double FramesPerSecond = 24.0;

// Appends `values` to the buffer (4-byte aligned) and adds a view and an accessor for them.
int addAccessor(tinygltf::Model& model, const std::vector<float>& values, int type,
                std::size_t count, bool withBounds, int target)
{
  auto& data = model.buffers[0].data;
  data.resize((data.size() + 3) & ~std::size_t{3});
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = data.size();
  view.byteLength = values.size() * sizeof(float);
  if (target)
    view.target = target;
  const auto* bytes = reinterpret_cast<const unsigned char*>(values.data());
  data.insert(data.end(), bytes, bytes + view.byteLength);
  model.bufferViews.push_back(view);

  tinygltf::Accessor accessor;
  accessor.bufferView = static_cast<int>(model.bufferViews.size()) - 1;
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
    const std::size_t stride = indices ? 4 : 4 * (a.type == TINYGLTF_TYPE_VEC3 ? 3 : 1);
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

// One node with the mesh: the base shape, the triangles and a morph target per component.
void addMesh(tinygltf::Model& model, const MorphTargets& morph,
             const std::vector<std::int64_t>& triangles, std::size_t nv)
{
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

void writeGlb(const std::string& path, const CompressedSequence& sequence,
              const GlbOptions& options)
{
  const PcaModel& m = sequence.pca.model;
  if (m.layout != PcaLayout::Shapes)
    throw std::invalid_argument("glTF morph targets need the shape layout (basis = shapes)");
  if (sequence.triangles.empty())
    throw std::invalid_argument("glTF export needs triangles");
  const MorphTargets morph = morphTargetsOf(m);
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "DynamicPoints";
  model.buffers.resize(1);
  addMesh(model, morph, sequence.triangles, m.vertices);
  if (m.components() > 0 && m.frames > 1)
    addAnimation(model, morph.weights);

  // Written beside and renamed, so a failed write never leaves a broken file under the name.
  detail::writeBesideAndMove(path,
                             [&](const std::string& partial)
                             {
                               if (options.meshopt)
                                 writeMeshoptGlb(partial, path, model, m.vertices);
                               else if (!tinygltf::TinyGLTF().WriteGltfSceneToFile(
                                            &model, partial, true, true, false, true))
                                 throw std::runtime_error(path + ": cannot write the glTF file");
                             });
}

} // namespace dp

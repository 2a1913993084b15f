// SPDX-License-Identifier: BSD-3-Clause
// A depth rig's files (DepthRig.h): its description (rig.json), and a take's frames as the rig
// sees them written as a sequence.
#include "dp/geometry/DepthRig.h"

#include "dp/geometry/SurfaceSampler.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace dp
{

std::string DepthRig::description() const
{
  nlohmann::json rig;
  const DepthSensorModel& s = Sensor;
  rig["sensor"] = {{"name", s.name},
                   {"resolution", {s.width, s.height}},
                   {"fieldOfView", {s.horizontalFov, s.verticalFov}},
                   {"range", {s.nearRange, s.farRange}},
                   {"axialNoise", {s.c0, s.c1, s.c2, s.angular, s.angularPower}},
                   {"lateralNoise", {s.lateral, s.lateralAngular}},
                   {"depthUnit", s.depthUnit},
                   {"disparity", {s.focalBaseline, s.disparityStep}},
                   {"grazingLimit", s.grazingLimit},
                   {"mixedPixels", s.mixedPixels},
                   {"darkDropout", s.darkDropout}};
  rig["metresPerUnit"] = Scale;
  rig["captureVolume"] = {{Box[0], Box[1], Box[2]}, {Box[3], Box[4], Box[5]}};
  rig["cameras"] = nlohmann::json::array();
  for (std::size_t k = 0; k < cameras(); ++k)
  {
    const auto pose = [this](const DepthCamera& c)
    {
      std::array<double, 3> t;
      for (int i = 0; i < 3; ++i)
        t[static_cast<std::size_t>(i)] = c.translation[static_cast<std::size_t>(i)] / Scale;
      return nlohmann::json{{"rotation", c.rotation}, {"translation", t}};
    };
    rig["cameras"].push_back(
        {{"believed", pose(Believed[k])}, {"actual", pose(Actual[k])}, {"gain", Gains[k]}});
  }
  return rig.dump(2);
}

std::string writeRigSequence(const AnimatedMesh& take, const RigOptions& options,
                             const std::string& outDir, const SequenceWriteOptions& writing,
                             bool depthMeshes)
{
  const DepthRig rig(take, options);
  std::string series;
  if (!depthMeshes)
    series = writeFrameSequence(take, outDir, writing,
                                [&](const std::vector<double>& positions, std::size_t f)
                                { return rig.fusedCloud(positions, f); });
  for (std::size_t k = 0; depthMeshes && k < rig.cameras(); ++k)
  {
    const std::string folder =
        rig.cameras() == 1 ? outDir : (fs::path(outDir) / ("camera_" + std::to_string(k))).string();
    SequenceWriteOptions w = writing;
    w.writeGroundTruth = writing.writeGroundTruth && k == 0;
    const std::string written =
        writeFrameSequence(take, folder, w,
                           [&](const std::vector<double>& positions, std::size_t f)
                           { return rig.depthMesh(positions, k, f); });
    if (k == 0)
      series = written;
  }
  const std::string path = (fs::path(outDir) / "rig.json").string();
  std::ofstream out(path);
  out << rig.description() << "\n";
  if (!out)
    throw FileError(path, "cannot be written");
  return series;
}

} // namespace dp

// SPDX-License-Identifier: BSD-3-Clause
#include "Viewer.h"

#include "CommandLine.h"

#include <cstring>
#include <sstream>
#include <stdexcept>

namespace dp::cli
{
namespace
{

std::string base64(const std::vector<unsigned char>& bytes)
{
  static const char alphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3)
  {
    const unsigned a = bytes[i], b = i + 1 < bytes.size() ? bytes[i + 1] : 0u,
                   c = i + 2 < bytes.size() ? bytes[i + 2] : 0u;
    const unsigned triple = (a << 16) | (b << 8) | c;
    out += alphabet[(triple >> 18) & 63];
    out += alphabet[(triple >> 12) & 63];
    out += i + 1 < bytes.size() ? alphabet[(triple >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? alphabet[triple & 63] : '=';
  }
  return out;
}

// `page` with the one `placeholder` replaced by `text`.
void fill(std::string& page, const std::string& placeholder, const std::string& text)
{
  const std::size_t at = page.find(placeholder);
  if (at == std::string::npos)
    throw std::runtime_error("the viewer's template has no " + placeholder);
  page.replace(at, placeholder.size(), text);
}

// JSON inside a script element: "</" written as "<\/", so no text in it ends the element.
std::string scriptSafe(const std::string& json)
{
  std::string out;
  out.reserve(json.size());
  for (std::size_t i = 0; i < json.size(); ++i)
  {
    out += json[i];
    if (json[i] == '<' && i + 1 < json.size() && json[i + 1] == '/')
      out += '\\';
  }
  return out;
}

// A Python string literal of `text` (a path).
std::string quoted(const std::string& text)
{
  return nlohmann::json(text).dump();
}

// The state's opening lines: how to open it, the plugin loaded, the tracked take read.
void writeStateHead(std::ostream& s, const std::string& path, const StateInputs& in)
{
  s << "# ParaView state written by dynamicpoints: the tracked take coloured by its distance to\n"
       "# the points (Residual), the points over it, at the first frame; the time controls step\n"
       "# through the frames. Open it with\n"
       "#     paraview --state="
    << path
    << "\n"
       "# or run it in pvpython. The points are read by the DynamicPoints plugin.\n"
       "from paraview.simple import *\n"
       "import os\n\n"
       "PLUGIN = "
    << quoted(in.plugin)
    << "\n"
       "if PLUGIN and os.path.exists(PLUGIN):\n"
       "    LoadPlugin(PLUGIN, remote=False, ns=globals())\n"
       "tracked = PVDReader(registrationName='tracked', FileName="
    << quoted(in.tracked) << ")\n";
}

// The tracked take in a view of its own, coloured by its distance to the points.
void writeStateMesh(std::ostream& s, const StateInputs& in)
{
  s << "# A view of its own in a layout of its own: loading a state, ParaView clears its views.\n"
       "view = CreateView('RenderView')\n"
       "CreateLayout(name='DynamicPoints').AssignView(0, view)\n"
       "SetActiveView(view)\n"
       "mesh = Show(tracked, view)\n"
       "ColorBy(mesh, ('POINTS', 'Residual'))\n"
       "residual = GetColorTransferFunction('Residual')\n"
       "residual.ApplyPreset('Viridis (matplotlib)', True)\n"
       "residual.RescaleTransferFunction(0.0, "
    << (in.largestResidual > 0 ? in.largestResidual : 1.0)
    << ")\n"
       "residual.AutomaticRescaleRangeMode = 'Never'\n"
       "mesh.SetScalarBarVisibility(view, True)\n"
       "GetScalarBar(residual, view).Title = 'distance to the points'\n"
       "GetScalarBar(residual, view).ComponentTitle = ''\n";
}

// The points over the take, read by the plugin when it was loaded.
void writeStatePoints(std::ostream& s, const StateInputs& in)
{
  s << "if 'PointSequenceReader' in globals():\n";
  if (in.pattern.empty())
    s << "    points = PointSequenceReader(registrationName='points', FileNames=["
      << quoted(in.points) << "])\n";
  else
    s << "    points = PointSequenceFolder(registrationName='points', DirectoryName="
      << quoted(in.points) << ", FilePattern=" << quoted(in.pattern) << ")\n";
  s << "    cloud = Show(points, view)\n"
       "    cloud.SetRepresentationType('Points')\n"
       "    cloud.PointSize = 1.5\n"
       "    cloud.ColorArrayName = ['POINTS', '']\n"
       "    cloud.AmbientColor = cloud.DiffuseColor = [0.2, 0.2, 0.2]\n"
       "else:\n"
       "    print('the DynamicPoints plugin was not found at ' + repr(PLUGIN) + ': the points are "
       "not shown')\n";
}

// The scene at the first frame, its time steps those of the data.
void writeStateScene(std::ostream& s)
{
  s << "scene = GetAnimationScene()\n"
       "scene.UpdateAnimationUsingDataTimeSteps()\n"
       "scene.PlayMode = 'Snap To TimeSteps'\n"
       "times = tracked.TimestepValues\n"
       "times = list(times) if hasattr(times, '__len__') else [times]\n"
       "scene.AnimationTime = times[0] if times else 0.0\n"
       "view.ResetCamera()\n"
       "SetActiveSource(tracked)\n"
       "Render(view)\n";
}

} // namespace

bool viewerAvailable()
{
  return std::strlen(assets::threeScript()) > 0 && std::strlen(assets::orbitControlsScript()) > 0;
}

void writeViewerPage(const std::string& path, const std::vector<unsigned char>& glb,
                     const nlohmann::json& report)
{
  if (!viewerAvailable())
    throw std::runtime_error("this build has no three.js (Utilities/dp.sh installs it from npm "
                             "before building)");
  std::string page = assets::viewerPage();
  fill(page, "/*DP_THREE*/", assets::threeScript());
  fill(page, "/*DP_ORBIT*/", assets::orbitControlsScript());
  fill(page, "/*DP_REPORT*/", scriptSafe(report.dump()));
  fill(page, "/*DP_GLB*/", base64(glb));
  writeAtomically(path, page);
}

void writeParaViewState(const std::string& path, const StateInputs& in)
{
  std::ostringstream s;
  writeStateHead(s, path, in);
  writeStateMesh(s, in);
  writeStatePoints(s, in);
  writeStateScene(s);
  writeAtomically(path, s.str());
}

} // namespace dp::cli

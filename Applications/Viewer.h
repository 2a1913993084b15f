// SPDX-License-Identifier: BSD-3-Clause
// What the main job writes for looking at a take: a page that plays it in any browser (view.html:
// the take's .glb and report inside, three.js inline, no server, no network) and a ParaView state
// that opens the tracked take and its points together (paraview --state=paraview-state.py).
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace dp::cli
{

namespace assets
{
// Generated from Applications/viewer/ (EmbedViewer.cmake): the page's template and three.js
// (npm three@0.147.0, MIT licence); empty when three.js was not there at build time.
const char* viewerPage();
const char* threeScript();
const char* orbitControlsScript();
} // namespace assets

/** Whether this build can write the page (three.js was found when it was built). */
bool viewerAvailable();

/** Writes the page to `path` (beside its name, then moved into place): the template with
 *  three.js, `report` (report.json's content) and `glb` (a plain .glb's bytes: no meshopt)
 *  inside. Throws std::runtime_error when it cannot be written or the build has no three.js. */
void writeViewerPage(const std::string& path, const std::vector<unsigned char>& glb,
                     const nlohmann::json& report);

/** What the ParaView state opens. */
struct StateInputs
{
  std::string tracked;        // the tracked take (.pvd)
  std::string points;         // the input: a .series or point file, or a folder
  std::string pattern;        // the folder's file pattern
  std::string plugin;         // the DynamicPoints plugin (for the points); empty: none found
  double largestResidual = 0; // frame 0's largest: the colour map's top
};

/** Writes a ParaView Python state to `path`: the tracked take coloured by its distance to the
 *  points (Residual), the points over it, the time at the first frame, the scene's time steps
 *  those of the data. */
void writeParaViewState(const std::string& path, const StateInputs& inputs);

} // namespace dp::cli

// SPDX-License-Identifier: BSD-3-Clause
#include "dp/detail/DetailOptions.h"

#include "dp/geometry/SubdivisionMap.h"

namespace dp
{

namespace
{

using Rows = OptionRows<DetailOptions>;

std::vector<Rows::Row> detailRows()
{
  return {
      Rows::integer(
          "detail.levels", "DetailLevels", OptionPanel::Shown, AutomaticDetailLevels,
          MaximumDetailLevels,
          "subdivision levels of the fine mesh: 0 none, -1 measured on the first frame",
          [](auto& o) -> auto& { return o.levels; })
          .withHelp("Subdivision levels of the fine mesh (0: none, the tracked mesh passes "
                    "through; each level has four times the triangles of the one before). -1 "
                    "(default): measured on the first frame: the level whose fine mesh has about "
                    "the capture's vertex count (half its point count), kept where it lies at "
                    "least a fifth closer to the data than the tracked mesh, else none "
                    "(DetailChoice says what was measured)."),
      Rows::real(
          "detail.reach", "Reach", OptionPanel::Advanced, 0.01, 10, "mean edge lengths",
          "the farthest a fine vertex is moved onto the data; data farther along its "
          "normal count as none",
          [](auto& o) -> auto& { return o.reach; })
          .withHelp("The farthest a fine vertex is moved onto the data, in mean edge lengths of "
                    "the tracked mesh (default 1): data farther along its normal count as none."),
      Rows::real(
          "detail.smoothness", "Smoothness", OptionPanel::Advanced, 0, 100, "",
          "weight of the membrane term against the data's: it spans holes; more smooths "
          "the noise of point data away, and detail with it",
          [](auto& o) -> auto& { return o.smoothness; })
          .withHelp("Weight of the membrane term against the data's (default 0.02): it spans "
                    "holes; more smooths the noise of point data away, and detail with it."),
      Rows::real(
          "detail.normalAngle", "NormalTestAngle", OptionPanel::Advanced, 1, 90, "degrees",
          "data whose surface normal turns more than this from a fine vertex's is another "
          "surface's (the other side of a thin part, a limb touching the body), not followed",
          [](auto& o) -> auto& { return o.normalAngle; })
          .withHelp("Data whose surface normal turns more than this many degrees from a fine "
                    "vertex's is another surface's (the other side of a thin part, a limb "
                    "touching the body) and is not followed (default 80)."),
  };
}

} // namespace

const OptionTable<DetailOptions>& detailOptions()
{
  static const OptionTable<DetailOptions> table("detail option", detailRows());
  return table;
}

} // namespace dp

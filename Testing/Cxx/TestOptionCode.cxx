// SPDX-License-Identifier: BSD-3-Clause
// OptionCode.h: what the VTK classes, ParaView's XML and the documentation restate of an option
// table is written from the table. A row added to the tracker's table reaches each form (the
// accessors, the panel's property with its range, visibility, documentation and condition, the
// Markdown table, the command line's parse); regions are rewritten in place and nothing outside
// them changes; a malformed region is refused by file and line.
#include "dp/io/OptionCode.h"
#include "dp/track/TrackerOptionTable.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace
{

// The tracker's table with one more row, as a developer would add it.
dp::OptionTable<dp::TrackerOptions> trackerTableWithANewRow()
{
  using Rows = dp::OptionRows<dp::TrackerOptions>;
  std::vector<dp::OptionDescription<dp::TrackerOptions>> rows = dp::trackerOptions().rows();
  rows.push_back(Rows::real(
                     "restUpdate", "ReferenceBlend", dp::OptionPanel::Advanced, 0, 1, "",
                     "a new option's one line", [](auto& o) -> auto& { return o.restUpdate; })
                     .withHelp("A new option's longer documentation, with a < sign.")
                     .shownWith("CoarseLevel=1"));
  return dp::OptionTable<dp::TrackerOptions>("tracker option", std::move(rows));
}

std::size_t occurrences(const std::string& text, const std::string& what)
{
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
    ++n;
  return n;
}

} // namespace

TEST(OptionCode, ARowAddedToATableReachesEveryForm)
{
  const auto table = trackerTableWithANewRow();
  const dp::OptionCodeTable code = table.codeTable("TrackerOption");

  const std::string accessors = dp::vtkAccessors(code, {});
  EXPECT_NE(accessors.find("void SetReferenceBlend(double value) { "
                           "this->SetTrackerOption(\"ReferenceBlend\", value); }"),
            std::string::npos)
      << accessors;
  EXPECT_NE(accessors.find("double GetReferenceBlend()"), std::string::npos);
  EXPECT_NE(accessors.find("A new option's longer documentation"), std::string::npos);

  const std::string xml = dp::paraviewProperties(code, {});
  const std::size_t at = xml.find("<DoubleVectorProperty name=\"ReferenceBlend\"");
  ASSERT_NE(at, std::string::npos) << xml;
  const std::string property = xml.substr(at, xml.find("</DoubleVectorProperty>", at) - at);
  EXPECT_NE(property.find("command=\"SetReferenceBlend\""), std::string::npos);
  EXPECT_NE(property.find("default_values=\"0.3\""), std::string::npos) << property;
  EXPECT_NE(property.find("panel_visibility=\"advanced\""), std::string::npos);
  EXPECT_NE(property.find("<DoubleRangeDomain name=\"range\" min=\"0\" max=\"1\" />"),
            std::string::npos);
  EXPECT_NE(property.find("with a &lt; sign."), std::string::npos) << property;
  EXPECT_NE(property.find("property=\"CoarseLevel\" value=\"1\""), std::string::npos);

  const std::string markdown = table.describeMarkdown();
  EXPECT_NE(markdown.find("ReferenceBlend (advanced) | 0.3 | [0, 1]"), std::string::npos)
      << markdown;

  // The command line and the filters' generic accessor reach it by its property name.
  dp::TrackerOptions options;
  table.set(options, "ReferenceBlend", "0.75");
  EXPECT_EQ(options.restUpdate, 0.75);
}

TEST(OptionCode, EveryKindGetsItsAccessorsAndDomain)
{
  const dp::OptionCodeTable code = dp::trackerOptions().codeTable("TrackerOption");
  const std::string accessors = dp::vtkAccessors(code, {});
  const std::string xml = dp::paraviewProperties(code, {});
  // A flag: vtkTypeBool with On/Off, a boolean domain.
  EXPECT_NE(accessors.find("vtkBooleanMacro(Recovery, vtkTypeBool);"), std::string::npos);
  EXPECT_NE(xml.find("<BooleanDomain name=\"bool\" />"), std::string::npos);
  // A choice: an int, its entries labelled as the table says.
  EXPECT_NE(accessors.find("int GetSolver() { return static_cast<int>"), std::string::npos);
  EXPECT_NE(xml.find("<Entry value=\"2\" text=\"Steepest descent (paper)\" />"), std::string::npos);
  // A wide range gets no slider (no max), a narrow one does.
  EXPECT_NE(xml.find("name=\"GraphNodes\""), std::string::npos);
  EXPECT_EQ(xml.find("max=\"10000000\""), std::string::npos);
  EXPECT_NE(xml.find("min=\"0\" max=\"180\""), std::string::npos);
  // Properties left out of a region are not written; rows without a property never are.
  EXPECT_EQ(dp::paraviewProperties(code, {"Solver"}).find("name=\"Solver\""), std::string::npos);
  EXPECT_EQ(occurrences(xml, "command=\"Set"), dp::presentedRows(code, {}).size());
  EXPECT_EQ(xml.find("softening.bend"), std::string::npos);
}

TEST(OptionCode, RegionsAreRewrittenInPlaceAndNothingElse)
{
  const std::string text = "before\n"
                           "  // BEGIN generated options: tracker except Solver,Recovery\n"
                           "  stale line\n"
                           "  // END generated options\n"
                           "after\n";
  dp::OptionRegion seen;
  const std::string out = dp::rewriteOptionRegions(text, "f.h",
                                                   [&](const dp::OptionRegion& r)
                                                   {
                                                     seen = r;
                                                     return std::string("  fresh\n");
                                                   });
  EXPECT_EQ(out, "before\n"
                 "  // BEGIN generated options: tracker except Solver,Recovery\n"
                 "  fresh\n"
                 "  // END generated options\n"
                 "after\n");
  EXPECT_EQ(seen.table, "tracker");
  EXPECT_EQ(seen.except, (std::vector<std::string>{"Solver", "Recovery"}));
  // Written again, nothing changes.
  EXPECT_EQ(dp::rewriteOptionRegions(
                out, "f.h", [](const dp::OptionRegion&) { return std::string("  fresh\n"); }),
            out);
}

TEST(OptionCode, AMalformedRegionIsRefusedByFileAndLine)
{
  const auto refusal = [](const std::string& text)
  {
    try
    {
      dp::rewriteOptionRegions(text, "panel.xml", [](const dp::OptionRegion&) { return ""; });
    }
    catch (const std::invalid_argument& e)
    {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(refusal("a\n<!-- BEGIN generated options: tracker -->\nb\n"),
            "panel.xml: a region does not end ('END generated options')");
  EXPECT_EQ(refusal("a\n<!-- END generated options -->\n"),
            "panel.xml:2: a region ends that did not begin");
  EXPECT_EQ(refusal("BEGIN generated options: tracker\nBEGIN generated options: tracker\n"),
            "panel.xml:2: a region begins inside another");
  EXPECT_NE(refusal("<!-- BEGIN generated options: -->\n<!-- END generated options -->\n")
                .find("names no table"),
            std::string::npos);
}

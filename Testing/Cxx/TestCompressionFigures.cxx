// SPDX-License-Identifier: BSD-3-Clause
// CompressionFigures: a compressed take's figures, declared once. Every member is in the table
// once under a name of its own; the codec's figures are the report's, the components per frame
// counted by the layout's allowance, colour and detail figures present exactly when the take has
// them; the Markdown table lists each.
#include "dp/compress/CompressionFigures.h"
#include "dp/compress/PcaCompression.h"

#include "TestUtilities.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

namespace
{

TEST(CompressionFigures, EveryMemberIsListedOnceUnderANameOfItsOwn)
{
  // Every member is a double: as many fields as doubles in the record, each reading back the
  // value written through it, lists them all.
  const auto& fields = dp::CompressionFigures::fields();
  EXPECT_EQ(fields.size() * sizeof(double), sizeof(dp::CompressionFigures));
  dp::CompressionFigures figures;
  for (std::size_t i = 0; i < fields.size(); ++i)
    figures.*fields[i].value = static_cast<double>(i + 1);
  std::set<std::string> names;
  for (std::size_t i = 0; i < fields.size(); ++i)
  {
    EXPECT_EQ(figures.*fields[i].value, static_cast<double>(i + 1))
        << "a member listed twice: " << fields[i].name;
    EXPECT_TRUE(names.insert(fields[i].name).second) << "twice: " << fields[i].name;
  }
  // Counts are the whole numbers: components, bytes, levels, flags; errors and ratios are not.
  for (const auto& f : fields)
  {
    const std::string name = f.name;
    if (name == "Components" || name == "ColourBytes" || name == "DetailLevels")
    {
      EXPECT_TRUE(f.count) << name;
    }
    if (name == "KGError" || name == "PaperRatio" || name == "DetailStep")
    {
      EXPECT_FALSE(f.count) << name;
    }
  }
}

TEST(CompressionFigures, TheCodecsFiguresAreItsReportsCountedByLayout)
{
  dp::CompressedSequence s;
  s.report.components = 6;
  s.report.paperD0 = 3000;
  s.report.paperD1 = 600;
  s.report.paperRatio = 5;
  s.report.bitsPerVertexFrame = 2.5;
  s.report.quantisedPlainBits = 9.5;
  s.report.kgError = 0.2;
  s.report.maxError = 0.01;
  s.report.maxErrorRelative = 0.001;
  s.report.rmsError = 0.004;
  s.pca.model.layout = dp::PcaLayout::Trajectories;
  dp::CompressionFigures f = dp::CompressionFigures::of(s, 10);
  EXPECT_EQ(f.components, 6);
  EXPECT_EQ(f.layout, 0);
  EXPECT_EQ(f.paperD0, 3000);
  EXPECT_EQ(f.paperD1, 600);
  EXPECT_EQ(f.paperRatio, 5);
  EXPECT_EQ(f.bitsPerVertexFrame, 2.5);
  EXPECT_EQ(f.quantisedPlainBits, 9.5);
  EXPECT_EQ(f.kgError, 0.2);
  EXPECT_EQ(f.maxError, 0.01);
  EXPECT_EQ(f.maxErrorRelative, 0.001);
  EXPECT_EQ(f.rmsError, 0.004);
  EXPECT_EQ(f.componentsPerFrame, 6.0 / 30); // three a frame in trajectories (x y z)
  // No colour, no detail, nothing against the data: those figures do not apply.
  for (const double none : {f.colourBytes, f.colourTolerance, f.detailLevels, f.detailBytes,
                            f.detailStep, f.distanceToDataInput, f.slid})
    EXPECT_TRUE(std::isnan(none));

  s.pca.model.layout = dp::PcaLayout::Shapes;
  s.colours.assign(3 * 4 * 10, 7);
  s.report.colourBytes = 321;
  s.report.colourTolerance = 2;
  s.detail.levels = 2;
  s.detail.step = 0.0005;
  s.report.detailBytes = 4096;
  f = dp::CompressionFigures::of(s, 10);
  EXPECT_EQ(f.layout, 1);
  EXPECT_EQ(f.componentsPerFrame, 6.0 / 10); // one a frame in shapes
  EXPECT_EQ(f.colourBytes, 321);
  EXPECT_EQ(f.colourTolerance, 2);
  EXPECT_EQ(f.detailLevels, 2);
  EXPECT_EQ(f.detailStep, 0.0005);
  EXPECT_EQ(f.detailBytes, 4096);
  EXPECT_TRUE(std::isnan(f.detailDistanceToDataInput)); // the caller's to fill
}

TEST(CompressionFigures, ACompressedTakesFiguresAreItsReports)
{
  const dp::CompressedSequence c = dp::test::compressedTube(12);
  const dp::CompressionFigures f = dp::CompressionFigures::of(c, 12);
  EXPECT_EQ(f.components, static_cast<double>(c.report.components));
  EXPECT_EQ(f.components, static_cast<double>(c.pca.model.components()));
  EXPECT_EQ(f.kgError, c.report.kgError);
  EXPECT_EQ(f.layout, static_cast<double>(c.pca.model.layout));
  const double allowed = c.pca.model.layout == dp::PcaLayout::Trajectories ? 36 : 12;
  EXPECT_EQ(f.componentsPerFrame, f.components / allowed);
}

TEST(CompressionFigures, TheMarkdownTableListsEachFigure)
{
  const std::string md = dp::CompressionFigures::markdown();
  EXPECT_EQ(md.rfind("| field data and report.json | what |\n|---|---|\n", 0), 0u);
  std::size_t rows = 0;
  for (char c : md)
    rows += c == '\n';
  EXPECT_EQ(rows, 2 + dp::CompressionFigures::fields().size());
  for (const auto& f : dp::CompressionFigures::fields())
    EXPECT_NE(md.find(std::string("| `") + f.name + "` | " + f.doc + " |\n"), std::string::npos)
        << f.name;
}

} // namespace

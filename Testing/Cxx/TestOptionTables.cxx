// SPDX-License-Identifier: BSD-3-Clause
// The option tables (OptionTable.h: the tracker's and the compression's): every option described
// once; its accessors reach the field its name spells, validation refuses each option out of
// its range by name, text and the JSON the command line reads and writes round-trip, and a
// filter's clamp keeps a value in range.
#include "dp/compress/CompressionOptions.h"
#include "dp/track/TrackerOptionTable.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>

namespace
{

struct TrackerTable
{
  using Options = dp::TrackerOptions;
  static const dp::OptionTable<Options>& table() { return dp::trackerOptions(); }
  static void check(const Options& o) { dp::checkTrackerOptions(o); }
  static constexpr const char* what = "tracker option ";
  static constexpr std::size_t atLeast = 45;
};

struct CompressionTable
{
  using Options = dp::CompressionOptions;
  static const dp::OptionTable<Options>& table() { return dp::compressionOptions(); }
  static void check(const Options& o) { dp::pcaOptionsOf(o); }
  static constexpr const char* what = "compression option ";
  static constexpr std::size_t atLeast = 8;
};

template <typename Table>
std::string refusal(const typename Table::Options& o)
{
  try
  {
    Table::check(o);
  }
  catch (const std::invalid_argument& e)
  {
    return e.what();
  }
  return "";
}

template <typename Table>
class OptionTables : public ::testing::Test
{
};
using Tables = ::testing::Types<TrackerTable, CompressionTable>;
TYPED_TEST_SUITE(OptionTables, Tables);

TYPED_TEST(OptionTables, EachOptionOnceWithItsDefaultInItsRange)
{
  const typename TypeParam::Options defaults;
  std::set<std::string> names, properties;
  for (const auto& row : TypeParam::table())
  {
    EXPECT_TRUE(names.insert(row.name).second) << "twice: " << row.name;
    if (!row.property.empty())
    {
      EXPECT_TRUE(properties.insert(row.property).second) << "twice: " << row.property;
    }
    EXPECT_FALSE(row.doc.empty()) << row.name;
    EXPECT_TRUE(row.accepts(row.get(defaults))) << row.name << " default out of its own range";
    EXPECT_EQ(&TypeParam::table().find(row.name), &row);
    if (!row.property.empty())
    {
      EXPECT_EQ(&TypeParam::table().find(row.property), &row);
    }
  }
  EXPECT_GE(names.size(), TypeParam::atLeast);
  EXPECT_EQ(refusal<TypeParam>(defaults), "");
  EXPECT_THROW(TypeParam::table().find("graph.yieldrate"), std::invalid_argument);
}

TYPED_TEST(OptionTables, EachAccessorReachesItsOwnFieldOnly)
{
  // Setting one option to another value in its range changes it and nothing else.
  using Options = typename TypeParam::Options;
  for (const auto& row : TypeParam::table())
  {
    Options o;
    const double before = row.get(o);
    const double other = before != row.minimum ? row.minimum : row.minimum + 1;
    if (!row.accepts(other))
      continue;
    row.set(o, other);
    EXPECT_EQ(row.get(o), other) << row.name;
    for (const auto& rest : TypeParam::table())
    {
      if (&rest != &row)
      {
        EXPECT_EQ(rest.get(o), rest.get(Options{})) << row.name << " moved " << rest.name;
      }
    }
  }
}

TYPED_TEST(OptionTables, EachOptionOutOfRangeIsRefusedByName)
{
  using Options = typename TypeParam::Options;
  const double nan = std::nan("");
  for (const auto& row : TypeParam::table())
  {
    if (row.kind == dp::OptionKind::Flag || row.kind == dp::OptionKind::Choice)
      continue; // a bool or an enum cannot hold a value out of range
    for (double bad : {row.minimum - 1, row.maximum * 2, nan})
    {
      if (row.accepts(bad) || (bad < 0 && row.kind != dp::OptionKind::Real))
        continue; // unsigned fields cannot hold a negative value
      if (!std::isfinite(bad) && row.kind != dp::OptionKind::Real)
        continue;
      Options o;
      row.set(o, bad);
      if (row.accepts(row.get(o)))
        continue; // the field's type could not hold it (an int beyond its range)
      EXPECT_NE(refusal<TypeParam>(o).find(TypeParam::what + row.name + ":"), std::string::npos)
          << row.name << " = " << bad << ": " << refusal<TypeParam>(o);
    }
  }
}

TYPED_TEST(OptionTables, ValuesJsonRoundTripsAndBadJsonIsRefusedByFile)
{
  using Options = typename TypeParam::Options;
  const auto& table = TypeParam::table();
  Options o;
  // Every option moved within its range: its top, or its bottom where the default is the top.
  for (const auto& row : table)
  {
    const double top = row.maximum == dp::Unbounded ? row.minimum + 7 : row.maximum;
    row.set(o, row.get(o) != top ? top : row.minimum);
  }
  Options back;
  table.readJson(back, table.valuesJson(o), "test");
  for (const auto& row : table)
  {
    EXPECT_EQ(row.get(back), row.get(o)) << row.name;
    EXPECT_NE(row.get(back), row.get(Options{})) << row.name << " was not moved";
  }
  for (const char* bad : {"[1]", "{\"nope\": 1}", "{"})
  {
    try
    {
      table.readJson(back, bad, "opts.json");
      ADD_FAILURE() << "accepted " << bad;
    }
    catch (const std::invalid_argument& e)
    {
      EXPECT_EQ(std::string(e.what()).rfind("opts.json: ", 0), 0u) << e.what();
    }
  }
}

TYPED_TEST(OptionTables, ClampKeepsAValueInRangeAndRefusesNaN)
{
  for (const auto& row : TypeParam::table())
  {
    for (double v : {-1e300, -1.0, 0.0, 0.5, 2.5, 1e300})
    {
      EXPECT_TRUE(row.accepts(row.clamped(v, "option"))) << row.name << " " << v;
    }
    if (row.accepts(row.minimum + 0.25) && row.kind == dp::OptionKind::Real)
    {
      EXPECT_EQ(row.clamped(row.minimum + 0.25, "option"), row.minimum + 0.25) << row.name;
    }
    EXPECT_THROW(row.clamped(std::nan(""), "option"), std::invalid_argument) << row.name;
  }
}

TEST(TrackerOptionTable, TextSetsTheFieldItNames)
{
  const auto& table = dp::trackerOptions();
  dp::TrackerOptions o;
  table.set(o, "graph.yieldRate", "0.25");
  table.set(o, "solver", "lbfgs");
  table.set(o, "CoarseLevel", "off");
  table.set(o, "distance.measure", "1");
  EXPECT_EQ(o.graph.yieldRate, 0.25);
  EXPECT_EQ(o.solver, dp::TrackerSolver::LBFGS);
  EXPECT_FALSE(o.graph.enabled);
  EXPECT_EQ(o.distance.measure, dp::DistanceMeasure::Points);
  EXPECT_THROW(table.set(o, "graph.yieldRate", "1.5"), std::invalid_argument);
  EXPECT_THROW(table.set(o, "graph.yieldRate", "0.2x"), std::invalid_argument);
  EXPECT_THROW(table.set(o, "solver", "newton"), std::invalid_argument);
  EXPECT_THROW(table.set(o, "graph.nodes", "2.5"), std::invalid_argument);

  dp::TrackerOptions partial;
  table.readJson(partial, R"({"colourWeight": 10, "recovery.enabled": false})", "f");
  EXPECT_EQ(partial.colourWeight, 10);
  EXPECT_FALSE(partial.recovery.enabled);
  EXPECT_THROW(table.readJson(partial, R"({"tolerance": 2})", "f"), std::invalid_argument);

  o.softening.from = 0.8; // above `to`: the tie between two options
  EXPECT_THROW(dp::checkTrackerOptions(o), std::invalid_argument);
}

TEST(CompressionOptionTable, EachMeasureReachesTheCodecWithItsOwnTarget)
{
  const auto& table = dp::compressionOptions();
  dp::CompressionOptions o;
  table.set(o, "compression.layout", "shapes");
  table.set(o, "NumberOfComponents", "12");
  table.set(o, "compression.quantise", "off");
  table.set(o, "compression.kgTarget", "0.05");
  table.set(o, "MaxVertexTarget", "0.01");
  dp::PcaOptions codec = dp::pcaOptionsOf(o);
  EXPECT_EQ(codec.layout, dp::PcaLayout::Shapes);
  EXPECT_EQ(codec.components, 12u);
  EXPECT_FALSE(codec.quantise);
  EXPECT_EQ(codec.measure, dp::PcaErrorMeasure::KarniGotsman);
  EXPECT_EQ(codec.target, 0.05);
  EXPECT_EQ(dp::targetSaid(o), "KG 0.05 %");

  table.set(o, "ErrorMeasure", "max-vertex");
  codec = dp::pcaOptionsOf(o);
  EXPECT_EQ(codec.measure, dp::PcaErrorMeasure::MaxVertexError);
  EXPECT_EQ(codec.target, 0.01);

  table.set(o, "compression.measure", "data");
  table.set(o, "FitGrowth", "25");
  EXPECT_EQ(o.measure, dp::CompressionMeasure::DistanceToData);
  EXPECT_EQ(o.fitGrowth, 25);
  EXPECT_EQ(dp::targetSaid(o), "the distance to the data grows by at most 25 %");

  // Each target's range is its own: a growth of 100 % is fine, a KG error of 100 % is not.
  EXPECT_NO_THROW(table.set(o, "compression.fitGrowth", "100"));
  EXPECT_THROW(table.set(o, "compression.kgTarget", "100"), std::invalid_argument);
  EXPECT_THROW(table.set(o, "compression.maxVertexTarget", "0"), std::invalid_argument);
  EXPECT_THROW(table.set(o, "compression.colourTolerance", "65"), std::invalid_argument);
  EXPECT_THROW(table.set(o, "compression.measure", "psnr"), std::invalid_argument);
}

} // namespace

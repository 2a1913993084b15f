// SPDX-License-Identifier: BSD-3-Clause
// The option tables (OptionTable.h: the tracker's and the compression's): every option described
// once; its accessors reach the field its name spells, validation refuses each option out of
// its range by name, text and the JSON the command line reads and writes round-trip, and a
// filter's clamp keeps a value in range. A small table of every kind of row checks OptionTable.h
// itself: each row maker, the ranges and values as users read them, and the descriptions.
#include "dp/compress/CompressionOptions.h"
#include "dp/detail/DetailOptions.h"
#include "dp/geometry/SubdivisionMap.h"
#include "dp/io/OptionTable.h"
#include "dp/track/TrackerOptionTable.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

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

// Options of every kind a table binds: a real, an integer, a flag, a choice held as an enum, an
// automatic value (0 or a range) and a nested member.
struct Toy
{
  enum class Mode
  {
    Alpha,
    Beta,
    Gamma
  };
  double rate = 0.5;
  int count = 3;
  bool on = true;
  Mode mode = Mode::Beta;
  double automatic = 0;
  struct
  {
    std::size_t depth = 2;
  } nested;
};

const dp::OptionTable<Toy>& toyTable()
{
  using Rows = dp::OptionRows<Toy>;
  static const dp::OptionTable<Toy> table(
      "toy option",
      {Rows::real(
           "rate", "Rate", dp::OptionPanel::Shown, 0, 1, "voxels", "a | rate",
           [](auto& o) -> auto& { return o.rate; })
           .withHelp("The rate, at length.")
           .withLabel("Rate of it"),
       Rows::integer(
           "count", "Count", dp::OptionPanel::Advanced, 1, 10, "a count",
           [](auto& o) -> auto& { return o.count; })
           .shownWith("On=1"),
       Rows::flag(
           "on", "On", dp::OptionPanel::Shown, "a switch", [](auto& o) -> auto& { return o.on; }),
       Rows::choice(
           "mode", "", dp::OptionPanel::None, {"alpha", "beta", "gamma"}, "a choice",
           [](auto& o) -> auto& { return o.mode; })
           .withChoiceLabels({"Alpha", "Beta", "Gamma"}),
       Rows::automatic(Rows::real(
           "automatic", "Automatic", dp::OptionPanel::Advanced, 100, dp::Unbounded, "points",
           "0 or a size", [](auto& o) -> auto& { return o.automatic; })),
       Rows::integer(
           "nested.depth", "Depth", dp::OptionPanel::None, 0, 5, "a nested count",
           [](auto& o) -> auto& { return o.nested.depth; })});
  return table;
}

// The message of the std::invalid_argument `call` throws ("" when it throws none).
template <typename Call>
std::string messageOf(Call call)
{
  try
  {
    call();
  }
  catch (const std::invalid_argument& e)
  {
    return e.what();
  }
  return "";
}

TEST(OptionTable, EachRowMakerBindsItsFieldWithItsKindAndPresentation)
{
  const auto& table = toyTable();
  ASSERT_EQ(table.rows().size(), 6u);
  EXPECT_EQ(table.what(), "toy option");
  const auto& rate = table.find("Rate");
  EXPECT_EQ(&rate, &table.find("rate"));
  EXPECT_EQ(rate.kind, dp::OptionKind::Real);
  EXPECT_EQ(rate.unit, "voxels");
  EXPECT_EQ(rate.help, "The rate, at length.");
  EXPECT_EQ(rate.label, "Rate of it");
  EXPECT_EQ(table.find("count").kind, dp::OptionKind::Integer);
  // (OptionDescription::shownWith, the row maker, hides the field of that name.)
  EXPECT_EQ(static_cast<const dp::OptionSpec&>(table.find("count")).shownWith, "On=1");
  EXPECT_EQ(table.find("count").panel, dp::OptionPanel::Advanced);
  EXPECT_TRUE(table.find("count").help.empty()); // presentation only where it was given
  EXPECT_EQ(table.find("on").kind, dp::OptionKind::Flag);
  EXPECT_EQ(table.find("mode").kind, dp::OptionKind::Choice);
  EXPECT_EQ(table.find("mode").maximum, 2);
  EXPECT_EQ(table.find("mode").choiceLabels, (std::vector<std::string>{"Alpha", "Beta", "Gamma"}));
  EXPECT_TRUE(table.find("automatic").zeroAllowed);
  EXPECT_FALSE(table.has("mode ") || table.has("")); // no row without a property is found by ""
  EXPECT_EQ(messageOf([&] { table.find("speed"); }), "no toy option 'speed'");

  // The accessors reach the struct's fields, a nested one too.
  Toy o;
  EXPECT_EQ(table.find("rate").get(o), 0.5);
  EXPECT_EQ(table.find("mode").get(o), 1);
  EXPECT_EQ(table.find("on").get(o), 1);
  table.find("rate").set(o, 0.25);
  table.find("count").set(o, 7);
  table.find("on").set(o, 0);
  table.find("mode").set(o, 2);
  table.find("nested.depth").set(o, 4);
  EXPECT_EQ(o.rate, 0.25);
  EXPECT_EQ(o.count, 7);
  EXPECT_FALSE(o.on);
  EXPECT_EQ(o.mode, Toy::Mode::Gamma);
  EXPECT_EQ(o.nested.depth, 4u);
}

TEST(OptionTable, RangesAndValuesReadAsUsersWriteThem)
{
  const auto& table = toyTable();
  EXPECT_EQ(table.find("rate").range(), "[0, 1]");
  EXPECT_EQ(table.find("count").range(), "[1, 10]");
  EXPECT_EQ(table.find("on").range(), "true|false");
  EXPECT_EQ(table.find("mode").range(), "alpha|beta|gamma");
  EXPECT_EQ(table.find("automatic").range(), "0 or [100, inf]");
  EXPECT_EQ(table.find("on").said(1), "true");
  EXPECT_EQ(table.find("mode").said(2), "gamma");
  EXPECT_EQ(table.find("count").said(7), "7");

  // accepts: in range, whole for every kind but a real, 0 where automatic; never NaN.
  EXPECT_TRUE(table.find("rate").accepts(0.3));
  EXPECT_FALSE(table.find("rate").accepts(1.01));
  EXPECT_FALSE(table.find("rate").accepts(std::nan("")));
  EXPECT_FALSE(table.find("count").accepts(2.5));
  EXPECT_TRUE(table.find("automatic").accepts(0));
  EXPECT_FALSE(table.find("automatic").accepts(50));
  EXPECT_TRUE(table.find("automatic").accepts(1e12));
  EXPECT_FALSE(table.find("automatic").accepts(HUGE_VAL));

  // Text: numbers, flag words, choice names or indices; a refusal names the option and its range.
  Toy o;
  table.set(o, "Rate", "0.75");
  table.set(o, "on", "off");
  table.set(o, "mode", "alpha");
  table.set(o, "automatic", "250");
  EXPECT_EQ(o.rate, 0.75);
  EXPECT_FALSE(o.on);
  EXPECT_EQ(o.mode, Toy::Mode::Alpha);
  EXPECT_EQ(o.automatic, 250);
  table.set(o, "on", "yes");
  table.set(o, "mode", "1");
  EXPECT_TRUE(o.on);
  EXPECT_EQ(o.mode, Toy::Mode::Beta);
  EXPECT_EQ(messageOf([&] { table.set(o, "rate", "fast"); }),
            "toy option rate wants [0, 1], not 'fast'");
  EXPECT_EQ(messageOf([&] { table.set(o, "mode", "delta"); }),
            "toy option mode wants alpha|beta|gamma, not 'delta'");
  EXPECT_EQ(messageOf([&] { table.set(o, "count", "11"); }),
            "toy option count: 11 is out of its range [1, 10] (a count)");
  EXPECT_NE(messageOf([&] { table.set(o, "count", "2.5"); }), "");
  EXPECT_NE(messageOf([&] { table.set(o, "on", "2"); }), "");
  EXPECT_NE(messageOf([&] { table.set(o, "automatic", "50"); }), "");

  // Clamped: into the range (whole for an integer), 0 kept where automatic; NaN refused.
  EXPECT_EQ(table.find("rate").clamped(7, "toy option"), 1);
  EXPECT_EQ(table.find("rate").clamped(-7, "toy option"), 0);
  EXPECT_EQ(table.find("count").clamped(4.6, "toy option"), 5);
  EXPECT_EQ(table.find("automatic").clamped(0, "toy option"), 0);
  EXPECT_EQ(table.find("automatic").clamped(3, "toy option"), 100);
  EXPECT_EQ(messageOf([&] { table.find("rate").clamped(std::nan(""), "toy option"); }),
            "toy option rate: NaN is no value");
}

TEST(OptionTable, CheckRefusesTheFirstOptionOutOfRangeAndJsonRoundTrips)
{
  const auto& table = toyTable();
  Toy o;
  EXPECT_EQ(messageOf([&] { table.check(o); }), "");
  o.count = 0;
  o.automatic = 5;
  EXPECT_EQ(messageOf([&] { table.check(o); }),
            "toy option count: 0 is out of its range [1, 10] (a count)");
  o.count = 10;
  EXPECT_EQ(messageOf([&] { table.check(o); }),
            "toy option automatic: 5 is out of its range 0 or [100, inf] (0 or a size)");

  o = Toy{};
  o.rate = 0.125;
  o.on = false;
  o.mode = Toy::Mode::Gamma;
  o.automatic = 1e6;
  o.nested.depth = 5;
  const std::string json = table.valuesJson(o);
  const nlohmann::json parsed = nlohmann::json::parse(json);
  EXPECT_EQ(parsed.at("on"), false);       // a flag as true/false
  EXPECT_EQ(parsed.at("mode"), "gamma");   // a choice by name
  EXPECT_EQ(parsed.at("nested.depth"), 5); // an integer as one
  EXPECT_EQ(parsed.at("rate"), 0.125);
  Toy back;
  table.readJson(back, json, "toy.json");
  for (const auto& row : table)
    EXPECT_EQ(row.get(back), row.get(o)) << row.name;
  EXPECT_EQ(messageOf([&] { table.readJson(back, R"({"count": 99})", "toy.json"); }),
            "toy.json: toy option count: 99 is out of its range [1, 10] (a count)");
  EXPECT_EQ(messageOf([&] { table.readJson(back, "[]", "toy.json"); }).rfind("toy.json: ", 0), 0u);
}

TEST(OptionTable, DescriptionsListEveryRowWithItsDefault)
{
  const auto& table = toyTable();
  const nlohmann::json rows = nlohmann::json::parse(table.describeJson());
  ASSERT_EQ(rows.size(), table.rows().size());
  EXPECT_EQ(rows[0].at("name"), "rate");
  EXPECT_EQ(rows[0].at("kind"), "real");
  EXPECT_EQ(rows[0].at("default"), 0.5);
  EXPECT_EQ(rows[0].at("panel"), "shown");
  EXPECT_EQ(rows[1].at("kind"), "integer");
  EXPECT_EQ(rows[1].at("panel"), "advanced");
  EXPECT_EQ(rows[2].at("default"), true);
  EXPECT_EQ(rows[3].at("default"), "beta");
  EXPECT_EQ(rows[3].at("value"), 1);
  EXPECT_EQ(rows[3].at("choices").get<std::vector<std::string>>(),
            (std::vector<std::string>{"alpha", "beta", "gamma"}));
  EXPECT_TRUE(rows[4].at("maximum").is_null()); // unbounded
  EXPECT_EQ(rows[4].at("zero_allowed"), true);

  // The Markdown: a header, then a row per option; a "|" in the text is escaped.
  const std::string md = table.describeMarkdown();
  std::vector<std::string> lines;
  for (std::size_t at = 0, end; at < md.size(); at = end + 1)
  {
    end = md.find('\n', at);
    lines.push_back(md.substr(at, end - at));
  }
  ASSERT_EQ(lines.size(), 2 + table.rows().size());
  EXPECT_EQ(lines[2], "| `rate` | Rate | 0.5 | [0, 1] | voxels | a \\| rate |");
  EXPECT_EQ(lines[3], "| `count` | Count (advanced) | 3 | [1, 10] |  | a count |");
  EXPECT_EQ(lines[5], "| `mode` |  | \"beta\" | alpha\\|beta\\|gamma |  | a choice |");

  const dp::OptionCodeTable code = table.codeTable("ToyOption");
  EXPECT_EQ(code.accessorFamily, "ToyOption");
  ASSERT_EQ(code.specs.size(), table.rows().size());
  EXPECT_EQ(code.specs[1], &table.rows()[1]);
  EXPECT_EQ(code.defaults, (std::vector<double>{0.5, 3, 1, 1, 0, 2}));
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

// The detail layer's table: its defaults are the fitter's, its levels end at the subdivision's
// bound (the one constant every form of it reads), and out-of-range text is refused by name.
TEST(DetailOptionTable, DefaultsAndBoundsAreTheEnginesAndTextOutOfRangeIsRefused)
{
  const auto& table = dp::detailOptions();
  const dp::DetailOptions defaults;
  EXPECT_EQ(defaults.levels, dp::AutomaticDetailLevels);
  EXPECT_EQ(defaults.smoothness, dp::DisplacementFitOptions{}.smoothness);
  EXPECT_EQ(defaults.normalAngle, dp::DisplacementFitOptions{}.normalAngle);
  const auto& levels = table.find("DetailLevels");
  EXPECT_EQ(levels.name, "detail.levels");
  EXPECT_EQ(levels.maximum, dp::MaximumDetailLevels);
  EXPECT_EQ(levels.minimum, dp::AutomaticDetailLevels);
  EXPECT_EQ(levels.clamped(99, table.what()), dp::MaximumDetailLevels);

  dp::DetailOptions options;
  table.set(options, "detail.levels", "2");
  table.set(options, "NormalTestAngle", "45");
  EXPECT_EQ(options.levels, 2);
  EXPECT_EQ(options.normalAngle, 45);
  try
  {
    table.set(options, "detail.levels", std::to_string(dp::MaximumDetailLevels + 1));
    FAIL() << "a level beyond the bound was accepted";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("detail.levels"), std::string::npos) << e.what();
  }
  EXPECT_EQ(options.levels, 2);
  EXPECT_THROW(table.find("detail.nothing"), std::invalid_argument);
}

// SPDX-License-Identifier: BSD-3-Clause
// TrackerOptionTable: every option described once; its accessors reach the field its name
// spells, validation refuses each option out of its range by name, and the JSON the command
// line reads and writes round-trips.
#include "dp/track/TrackerOptionTable.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>

namespace
{

std::string refusal(const dp::TrackerOptions& o)
{
  try
  {
    dp::checkTrackerOptions(o);
  }
  catch (const std::invalid_argument& e)
  {
    return e.what();
  }
  return "";
}

TEST(TrackerOptionTable, EachOptionOnceWithItsDefaultInItsRange)
{
  const dp::TrackerOptions defaults;
  std::set<std::string> names, properties;
  for (const dp::TrackerOptionDescription& row : dp::trackerOptionTable())
  {
    EXPECT_TRUE(names.insert(row.name).second) << "twice: " << row.name;
    if (!row.property.empty())
    {
      EXPECT_TRUE(properties.insert(row.property).second) << "twice: " << row.property;
    }
    EXPECT_FALSE(row.doc.empty()) << row.name;
    EXPECT_TRUE(row.accepts(row.get(defaults))) << row.name << " default out of its own range";
    EXPECT_EQ(&dp::trackerOption(row.name), &row);
    if (!row.property.empty())
    {
      EXPECT_EQ(&dp::trackerOption(row.property), &row);
    }
  }
  EXPECT_GE(names.size(), 45u);
  EXPECT_EQ(refusal(defaults), "");
  EXPECT_THROW(dp::trackerOption("graph.yieldrate"), std::invalid_argument);
}

TEST(TrackerOptionTable, EachAccessorReachesItsOwnFieldOnly)
{
  // Setting one option to another value in its range changes it and nothing else.
  for (const dp::TrackerOptionDescription& row : dp::trackerOptionTable())
  {
    dp::TrackerOptions o;
    const double before = row.get(o);
    const double other = before != row.minimum ? row.minimum : row.minimum + 1;
    if (!row.accepts(other))
      continue;
    row.set(o, other);
    EXPECT_EQ(row.get(o), other) << row.name;
    for (const dp::TrackerOptionDescription& rest : dp::trackerOptionTable())
    {
      if (&rest != &row)
      {
        EXPECT_EQ(rest.get(o), rest.get(dp::TrackerOptions{}))
            << row.name << " moved " << rest.name;
      }
    }
  }
  dp::TrackerOptions o;
  dp::trackerOption("graph.yieldRate").set(o, 0.7);
  EXPECT_EQ(o.graph.yieldRate, 0.7);
  dp::trackerOption("DistanceMeasure").set(o, 1);
  EXPECT_EQ(o.distance.measure, dp::DistanceMeasure::Points);
}

TEST(TrackerOptionTable, EachOptionOutOfRangeIsRefusedByName)
{
  const double nan = std::nan("");
  for (const dp::TrackerOptionDescription& row : dp::trackerOptionTable())
  {
    if (row.kind == dp::OptionKind::Flag || row.kind == dp::OptionKind::Choice)
      continue; // a bool or an enum cannot hold a value out of range
    for (double bad : {row.minimum - 1, row.maximum * 2, nan})
    {
      if (row.accepts(bad) || (bad < 0 && row.kind != dp::OptionKind::Real))
        continue; // unsigned fields cannot hold a negative value
      if (!std::isfinite(bad) && row.kind != dp::OptionKind::Real)
        continue;
      dp::TrackerOptions o;
      row.set(o, bad);
      if (row.accepts(row.get(o)))
        continue; // the field's type could not hold it (an int beyond its range)
      EXPECT_NE(refusal(o).find("tracker option " + row.name + ":"), std::string::npos)
          << row.name << " = " << bad << ": " << refusal(o);
    }
  }
  dp::TrackerOptions o;
  o.softening.from = 0.8; // above `to`
  EXPECT_NE(refusal(o).find("softening.from"), std::string::npos);
}

TEST(TrackerOptionTable, TextAndJsonRoundTrip)
{
  dp::TrackerOptions o;
  dp::setTrackerOption(o, "graph.yieldRate", "0.25");
  dp::setTrackerOption(o, "solver", "lbfgs");
  dp::setTrackerOption(o, "CoarseLevel", "off");
  dp::setTrackerOption(o, "distance.measure", "1");
  EXPECT_EQ(o.graph.yieldRate, 0.25);
  EXPECT_EQ(o.solver, dp::TrackerSolver::LBFGS);
  EXPECT_FALSE(o.graph.enabled);
  EXPECT_EQ(o.distance.measure, dp::DistanceMeasure::Points);
  EXPECT_THROW(dp::setTrackerOption(o, "graph.yieldRate", "1.5"), std::invalid_argument);
  EXPECT_THROW(dp::setTrackerOption(o, "graph.yieldRate", "0.2x"), std::invalid_argument);
  EXPECT_THROW(dp::setTrackerOption(o, "solver", "newton"), std::invalid_argument);
  EXPECT_THROW(dp::setTrackerOption(o, "graph.nodes", "2.5"), std::invalid_argument);

  dp::TrackerOptions back;
  dp::readTrackerOptionsJson(back, dp::trackerOptionsJson(o), "test");
  for (const dp::TrackerOptionDescription& row : dp::trackerOptionTable())
    EXPECT_EQ(row.get(back), row.get(o)) << row.name;

  dp::TrackerOptions partial;
  dp::readTrackerOptionsJson(partial, R"({"colourWeight": 10, "recovery.enabled": false})", "f");
  EXPECT_EQ(partial.colourWeight, 10);
  EXPECT_FALSE(partial.recovery.enabled);
  for (const char* bad : {"[1]", "{\"nope\": 1}", "{\"tolerance\": 2}", "{"})
  {
    try
    {
      dp::readTrackerOptionsJson(partial, bad, "opts.json");
      ADD_FAILURE() << "accepted " << bad;
    }
    catch (const std::invalid_argument& e)
    {
      EXPECT_EQ(std::string(e.what()).rfind("opts.json: ", 0), 0u) << e.what();
    }
  }
}

} // namespace

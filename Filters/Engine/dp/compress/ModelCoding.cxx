// SPDX-License-Identifier: BSD-3-Clause
#include "dp/compress/ModelCoding.h"

#include "dp/compress/RangeCoder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace dp::compress
{
namespace
{

// Contexts: the component's rank in 8 groups (0, 1, 2-3, 4-7, ..., 64 and beyond), and the size
// of the residuals around (the bit width of their magnitude, capped).
constexpr int Groups = 8, NeighbourBuckets = 8, OwnBuckets = 4, TimeBuckets = 8;
constexpr int TimeOrders = 3; // none, the frame before, linear from the two before

int bitWidth(std::uint64_t v)
{
  int b = 0;
  for (; v; v >>= 1)
    ++b;
  return b;
}

int groupOf(std::size_t component)
{
  return std::min(Groups - 1, bitWidth(component));
}

std::uint64_t magnitude(std::int64_t v)
{
  return v < 0 ? 0 - static_cast<std::uint64_t>(v) : static_cast<std::uint64_t>(v);
}

double costOf(std::int64_t residual)
{
  return std::log2(1.0 + 2.0 * static_cast<double>(magnitude(residual)));
}

// A decoded value, refused beyond the limit (only a corrupt stream gives one).
std::int64_t checkedValue(std::int64_t v, const std::string& what)
{
  if (v > ValueLimit || v < -ValueLimit)
    throw std::runtime_error(what + ": a coded value is out of range (the file is corrupt)");
  return v;
}

void checkValue(std::int64_t v)
{
  if (v > ValueLimit || v < -ValueLimit)
    throw std::invalid_argument("model coding: a quantised value (" + std::to_string(v) +
                                ") is beyond +-2^60 steps");
}

/** The per-vertex integers as rows (row-major by vertex index), and each column's component. */
struct VertexRows
{
  std::size_t vertices = 0, columns = 0;
  std::vector<std::int64_t> values;
  std::vector<std::size_t> component;
};

// Shapes: the mean's x y z, then each basis vector's x y z (component 0 is the mean). Trajectories:
// the weight of each component.
VertexRows rowsOf(PcaLayout layout, std::size_t vertices, std::size_t k)
{
  VertexRows r;
  r.vertices = vertices;
  const bool shapes = layout == PcaLayout::Shapes;
  r.columns = shapes ? 3 + 3 * k : k;
  r.values.assign(vertices * r.columns, 0);
  for (std::size_t c = 0; c < r.columns; ++c)
    r.component.push_back(shapes ? c / 3 : c);
  return r;
}

// Where row value (v, c) lives in q's arrays (Model: QuantisedPca, const or not).
template <typename Model>
auto& modelValue(Model& q, PcaLayout layout, std::size_t vertices, std::size_t v, std::size_t c)
{
  if (layout == PcaLayout::Trajectories)
    return q.weightIntegers[c * vertices + v];
  if (c < 3)
    return q.meanIntegers[3 * v + c];
  const std::size_t j = (c - 3) / 3, axis = (c - 3) % 3;
  return q.basisIntegers[j * 3 * vertices + 3 * v + axis];
}

/** A sequence along time inside q's arrays: `count` values `stride` apart from `first`. */
struct TimeColumn
{
  std::size_t first, count, stride, component;
  bool inMean; // in meanIntegers, else in the other array of its layout
};

// Shapes: each component's weights (a value per frame). Trajectories: the centroid trajectory,
// then each basis vector (x y z per frame, stride 3 so x follows x).
std::vector<TimeColumn> timeColumnsOf(PcaLayout layout, std::size_t frames, std::size_t k)
{
  std::vector<TimeColumn> columns;
  if (layout == PcaLayout::Shapes)
    for (std::size_t j = 0; j < k; ++j)
      columns.push_back({j * frames, frames, 1, j, false});
  else
  {
    const std::size_t rows = 3 * frames;
    for (std::size_t axis = 0; axis < 3; ++axis)
      columns.push_back({axis, frames, 3, 0, true});
    for (std::size_t j = 0; j < k; ++j)
      for (std::size_t axis = 0; axis < 3; ++axis)
        columns.push_back({j * rows + axis, frames, 3, j + 1, false});
  }
  return columns;
}

template <typename Model>
auto* timeData(Model& q, PcaLayout layout, const TimeColumn& c)
{
  if (c.inMean)
    return q.meanIntegers.data();
  return layout == PcaLayout::Shapes ? q.weightIntegers.data() : q.basisIntegers.data();
}

std::int64_t timePrediction(const std::int64_t* v, const TimeColumn& c, std::size_t i, int order)
{
  if (order == 0 || i == 0)
    return 0;
  const std::int64_t previous = v[c.first + (i - 1) * c.stride];
  if (order == 1 || i == 1)
    return previous;
  return 2 * previous - v[c.first + (i - 2) * c.stride];
}

/** The adaptive models of the residuals, one per context. */
class Models
{
public:
  Models() : Vertex(Groups * NeighbourBuckets * OwnBuckets), Time(Groups * TimeBuckets) {}
  IntegerModel& vertex(std::size_t component, std::uint64_t neighbours, std::uint64_t own)
  {
    const int n = std::min(NeighbourBuckets - 1, bitWidth(neighbours));
    const int o = std::min(OwnBuckets - 1, bitWidth(own));
    return Vertex[static_cast<std::size_t>(
        (groupOf(component) * NeighbourBuckets + n) * OwnBuckets + o)];
  }
  IntegerModel& time(std::size_t component, std::uint64_t previous)
  {
    const int p = std::min(TimeBuckets - 1, bitWidth(previous));
    return Time[static_cast<std::size_t>(groupOf(component) * TimeBuckets + p)];
  }

private:
  std::vector<IntegerModel> Vertex, Time;
};

/** The residuals coded so far, row-major by vertex index, for the contexts. */
class RowResiduals
{
public:
  explicit RowResiduals(const VertexRows& rows)
      : Columns(rows.columns), Values(rows.vertices * rows.columns, 0)
  {
  }
  void set(std::size_t v, std::size_t c, std::int64_t r) { Values[v * Columns + c] = r; }
  // The earlier neighbours' mean residual magnitude in column c, and v's own in the column before.
  std::uint64_t neighbours(const std::size_t* n, std::size_t count, std::size_t c) const
  {
    if (count == 0)
      return 0;
    double sum = 0;
    for (std::size_t i = 0; i < count; ++i)
      sum += static_cast<double>(magnitude(Values[n[i] * Columns + c]));
    return static_cast<std::uint64_t>(std::min(sum / static_cast<double>(count), 0x1p62));
  }
  std::uint64_t own(std::size_t v, std::size_t c) const
  {
    return c == 0 ? 0 : magnitude(Values[v * Columns + c - 1]);
  }

private:
  std::size_t Columns;
  std::vector<std::int64_t> Values;
};

/** Each per-vertex column's cheapest predictor (the values are exact: every predictor sees what
 *  the decoder will), and the regressions' predictions, kept for the coding pass (their solves
 *  are most of the coder's time). Without regressions, the mean or nothing. */
struct VertexPredictions
{
  std::vector<VertexPredictor> chosen;
  std::vector<std::int64_t> light, heavy; // row-major by vertex index, as the rows

  VertexPredictions(const VertexRows& rows, const VertexTraversal& t, bool regressions)
      : light(regressions ? rows.values.size() : 0), heavy(light.size())
  {
    const int predictors = regressions ? VertexPredictors : 2;
    std::vector<std::array<double, VertexPredictors>> cost(rows.columns);
    for (auto& c : cost)
      c.fill(std::numeric_limits<double>::infinity());
    for (auto& c : cost)
      std::fill(c.begin(), c.begin() + predictors, 0.0);
    for (std::size_t i = 0; i < t.vertices(); ++i)
    {
      const std::size_t v = t.order[i];
      RowPredictor predictor(rows.values.data(), rows.columns, t.earlier.data() + t.start[i],
                             t.start[i + 1] - t.start[i], v);
      for (std::size_t c = 0; c < rows.columns; ++c)
      {
        const std::size_t at = v * rows.columns + c;
        const std::int64_t value = rows.values[at];
        cost[c][0] += costOf(value);
        cost[c][1] += costOf(value - predictor.predict(c, VertexPredictor::Mean));
        if (regressions)
        {
          light[at] = predictor.predict(c, VertexPredictor::LightRegression);
          heavy[at] = predictor.predict(c, VertexPredictor::HeavyRegression);
          cost[c][2] += costOf(value - light[at]);
          cost[c][3] += costOf(value - heavy[at]);
        }
        predictor.learn(c);
      }
    }
    for (const auto& c : cost)
      chosen.push_back(
          static_cast<VertexPredictor>(std::min_element(c.begin(), c.end()) - c.begin()));
  }

  /** Entry (v, c)'s prediction by its column's predictor (`predictor`: v's, at column c). */
  std::int64_t operator()(RowPredictor& predictor, std::size_t at, std::size_t c) const
  {
    switch (chosen[c])
    {
    case VertexPredictor::LightRegression:
      return light[at];
    case VertexPredictor::HeavyRegression:
      return heavy[at];
    default:
      return predictor.predict(c, chosen[c]);
    }
  }
};

int chooseTimeOrder(const std::int64_t* v, const TimeColumn& c)
{
  int best = 0;
  double bestCost = std::numeric_limits<double>::infinity();
  for (int order = 0; order < TimeOrders; ++order)
  {
    double cost = 0;
    for (std::size_t i = 0; i < c.count; ++i)
      cost += costOf(v[c.first + i * c.stride] - timePrediction(v, c, i, order));
    if (cost < bestCost)
    {
      bestCost = cost;
      best = order;
    }
  }
  return best;
}

void putChoice(RangeEncoder& e, int value)
{
  e.evenBit(value >> 1);
  e.evenBit(value & 1);
}

int getChoice(RangeDecoder& d)
{
  const int high = d.evenBit();
  return 2 * high + d.evenBit();
}

/** The per-vertex rows coded entry by entry in the traversal's order; Coder: encodes or decodes
 *  the entry at `at` (column c) given its model and the vertex's RowPredictor, and returns its
 *  residual (the residuals around give the next entries' contexts). */
template <typename Coder>
void codeRows(Models& models, const VertexRows& rows, const VertexTraversal& t, Coder&& code)
{
  RowResiduals residuals(rows);
  for (std::size_t i = 0; i < t.vertices(); ++i)
  {
    const std::size_t v = t.order[i];
    const std::size_t* earlier = t.earlier.data() + t.start[i];
    const std::size_t count = t.start[i + 1] - t.start[i];
    RowPredictor predictor(rows.values.data(), rows.columns, earlier, count, v);
    for (std::size_t c = 0; c < rows.columns; ++c)
    {
      IntegerModel& model = models.vertex(
          rows.component[c], residuals.neighbours(earlier, count, c), residuals.own(v, c));
      residuals.set(v, c, code(model, predictor, v * rows.columns + c, c));
    }
  }
}

/** A time column coded value by value; Coder: encodes or decodes one residual given the model,
 *  the column's values, the index and the prediction, and returns the residual. */
template <typename Value, typename Coder>
void codeTimeColumn(Value* v, const TimeColumn& column, int order, Models& models, Coder&& code)
{
  std::int64_t previous = 0; // the residual a frame before
  for (std::size_t t = 0; t < column.count; ++t)
    previous = code(models.time(column.component, magnitude(previous)), v,
                    column.first + t * column.stride, timePrediction(v, column, t, order));
}

} // namespace

std::vector<std::uint8_t> encodeModel(const QuantisedPca& q, const VertexTraversal& traversal,
                                      ModelEffort effort)
{
  const PcaModel& m = q.model;
  const std::size_t k = m.components(), nv = traversal.vertices();
  for (const auto* part : {&q.meanIntegers, &q.basisIntegers, &q.weightIntegers})
    for (std::int64_t v : *part)
      checkValue(v);
  VertexRows rows = rowsOf(m.layout, nv, k);
  for (std::size_t v = 0; v < nv; ++v)
    for (std::size_t c = 0; c < rows.columns; ++c)
      rows.values[v * rows.columns + c] = modelValue(q, m.layout, nv, v, c);
  const VertexPredictions predictions(rows, traversal, effort == ModelEffort::Full);
  const std::vector<TimeColumn> columns = timeColumnsOf(m.layout, m.frames, k);

  RangeEncoder e;
  for (VertexPredictor p : predictions.chosen)
    putChoice(e, static_cast<int>(p));
  std::vector<int> orders;
  for (const TimeColumn& c : columns)
  {
    orders.push_back(chooseTimeOrder(timeData(q, m.layout, c), c));
    putChoice(e, orders.back());
  }
  Models models;
  codeRows(models, rows, traversal,
           [&](IntegerModel& model, RowPredictor& predictor, std::size_t at, std::size_t c)
           {
             const std::int64_t r = rows.values[at] - predictions(predictor, at, c);
             e.integer(model, r);
             return r;
           });
  for (std::size_t i = 0; i < columns.size(); ++i)
    codeTimeColumn(timeData(q, m.layout, columns[i]), columns[i], orders[i], models,
                   [&](IntegerModel& model, const std::int64_t* v, std::size_t at, std::int64_t p)
                   {
                     e.integer(model, v[at] - p);
                     return v[at] - p;
                   });
  return e.finish();
}

void decodeModel(const std::uint8_t* bytes, std::size_t size, const std::string& what,
                 const VertexTraversal& traversal, PcaLayout layout, std::size_t frames,
                 std::size_t components, QuantisedPca& q)
{
  const std::size_t nv = traversal.vertices(), k = components;
  const bool shapes = layout == PcaLayout::Shapes;
  q.meanIntegers.assign(shapes ? 3 * nv : 3 * frames, 0);
  q.basisIntegers.assign(k * (shapes ? 3 * nv : 3 * frames), 0);
  q.weightIntegers.assign(k * (shapes ? frames : nv), 0);
  VertexRows rows = rowsOf(layout, nv, k);
  const std::vector<TimeColumn> columns = timeColumnsOf(layout, frames, k);

  RangeDecoder d(bytes, size, what);
  std::vector<VertexPredictor> predictors;
  for (std::size_t c = 0; c < rows.columns; ++c)
    predictors.push_back(static_cast<VertexPredictor>(getChoice(d)));
  std::vector<int> orders;
  for (std::size_t i = 0; i < columns.size(); ++i)
  {
    orders.push_back(getChoice(d));
    if (orders.back() >= TimeOrders)
      throw std::runtime_error(what + ": unknown prediction order " +
                               std::to_string(orders.back()) + " (the file is corrupt)");
  }
  Models models;
  codeRows(models, rows, traversal,
           [&](IntegerModel& model, RowPredictor& predictor, std::size_t at, std::size_t c)
           {
             const std::int64_t r = d.integer(model);
             rows.values[at] = checkedValue(predictor.predict(c, predictors[c]) + r, what);
             predictor.learn(c);
             return r;
           });
  for (std::size_t v = 0; v < nv; ++v)
    for (std::size_t c = 0; c < rows.columns; ++c)
      modelValue(q, layout, nv, v, c) = rows.values[v * rows.columns + c];
  for (std::size_t i = 0; i < columns.size(); ++i)
    codeTimeColumn(timeData(q, layout, columns[i]), columns[i], orders[i], models,
                   [&](IntegerModel& model, std::int64_t* v, std::size_t at, std::int64_t p)
                   {
                     const std::int64_t r = d.integer(model);
                     v[at] = checkedValue(p + r, what);
                     return r;
                   });
  d.finish();
}

} // namespace dp::compress

// SPDX-License-Identifier: BSD-3-Clause
#include "FramePlot.h"

#include "vtkFreeTypeTools.h"
#include "vtkImageCanvasSource2D.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkSmartPointer.h"
#include "vtkStdString.h"
#include "vtkTextProperty.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>

namespace dp::cli
{
namespace
{

// Tick positions at 1, 2 or 5 times a power of ten, about `wanted` of them over [low, high].
std::vector<double> niceTicks(double low, double high, int wanted)
{
  const double raw = (high - low) / std::max(1, wanted);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  double step = power;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * power >= raw)
    {
      step = m * power;
      break;
    }
  std::vector<double> ticks;
  for (double t = std::ceil(low / step - 1e-9) * step; t <= high + 1e-9 * step; t += step)
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  return ticks;
}

std::string tickText(double v)
{
  char text[32];
  std::snprintf(text, sizeof(text), "%g", v);
  return text;
}

class Canvas
{
public:
  Canvas(int width, int height) : Width(width), Height(height)
  {
    Painter->SetScalarTypeToUnsignedChar();
    Painter->SetNumberOfScalarComponents(3);
    Painter->SetExtent(0, width - 1, 0, height - 1, 0, 0);
    Painter->SetDrawColor(255, 255, 255);
    Painter->FillBox(0, width - 1, 0, height - 1);
  }
  void colour(const std::array<unsigned char, 3>& c) { Painter->SetDrawColor(c[0], c[1], c[2]); }
  void box(int x0, int x1, int y0, int y1) { Painter->FillBox(x0, x1, y0, y1); }
  // A line `thickness` pixels wide, as parallel segments.
  void line(double x0, double y0, double x1, double y1, int thickness = 1)
  {
    const bool steep = std::abs(y1 - y0) > std::abs(x1 - x0);
    for (int o = -(thickness - 1) / 2; o <= thickness / 2; ++o)
      Painter->DrawSegment(static_cast<int>(std::lround(x0 + (steep ? o : 0))),
                           static_cast<int>(std::lround(y0 + (steep ? 0 : o))),
                           static_cast<int>(std::lround(x1 + (steep ? o : 0))),
                           static_cast<int>(std::lround(y1 + (steep ? 0 : o))));
  }
  // Text queued; drawn over the lines in finish(). alignX/alignY: 0 left/bottom, 1 centre,
  // 2 right/top of (x, y).
  void text(const std::string& s, int x, int y, int size, int alignX, int alignY, bool bold = false)
  {
    Texts.push_back({s, x, y, size, alignX, alignY, bold});
  }
  vtkSmartPointer<vtkImageData> finish()
  {
    Painter->Update();
    auto image = vtkSmartPointer<vtkImageData>::New();
    image->DeepCopy(Painter->GetOutput());
    vtkFreeTypeTools* freeType = vtkFreeTypeTools::GetInstance();
    for (const Text& t : Texts)
    {
      vtkNew<vtkTextProperty> property;
      property->SetFontSize(t.size);
      property->SetColor(0.1, 0.1, 0.1);
      property->SetBold(t.bold);
      vtkNew<vtkImageData> rendered;
      int dims[2] = {0, 0};
      if (!freeType->RenderString(property, vtkStdString(t.text), 72, rendered, dims))
        continue; // a label that cannot be drawn is not worth failing the report for
      int extent[6];
      rendered->GetExtent(extent);
      const int x0 = t.x - (t.alignX * dims[0]) / 2, y0 = t.y - (t.alignY * dims[1]) / 2;
      for (int j = 0; j < dims[1] && j <= extent[3]; ++j)
        for (int i = 0; i < dims[0] && i <= extent[1]; ++i)
        {
          const int x = x0 + i, y = y0 + j;
          if (x < 0 || y < 0 || x >= Width || y >= Height)
            continue;
          const auto* src = static_cast<unsigned char*>(rendered->GetScalarPointer(i, j, 0));
          auto* dst = static_cast<unsigned char*>(image->GetScalarPointer(x, y, 0));
          const double alpha = src[3] / 255.0;
          for (int c = 0; c < 3; ++c)
            dst[c] = static_cast<unsigned char>(std::lround((1 - alpha) * dst[c] + alpha * src[c]));
        }
    }
    return image;
  }

private:
  struct Text
  {
    std::string text;
    int x, y, size, alignX, alignY;
    bool bold;
  };
  int Width, Height;
  vtkNew<vtkImageCanvasSource2D> Painter;
  std::vector<Text> Texts;
};

// Where a panel sits on the canvas and the range of its values: maps frames and values to
// pixels.
struct PanelArea
{
  int x0, x1, y0, y1;
  double low, high, xMax;

  double px(double frame) const { return x0 + (x1 - x0) * frame / xMax; }
  double py(double value) const { return y0 + (y1 - y0) * (value - low) / (high - low); }
};

// The panel's area between the margins, and its value range: from zero (values here are sizes
// and times) to a little above the largest finite value.
PanelArea areaOf(const PlotPanel& panel, int x0, int x1, int y0, int y1)
{
  std::size_t frames = 0;
  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (const PlotLine& l : panel.lines)
  {
    frames = std::max(frames, l.values.size());
    for (double v : l.values)
      if (std::isfinite(v))
      {
        low = std::min(low, v);
        high = std::max(high, v);
      }
  }
  if (!std::isfinite(low))
    low = 0, high = 1;
  low = std::min(low, 0.0);
  if (high <= low)
    high = low + 1;
  high += 0.05 * (high - low);
  return {x0, x1, y0, y1, low, high, std::max<double>(1, static_cast<double>(frames) - 1)};
}

// The grid, its tick labels, the axes and their labels.
void drawAxes(Canvas& canvas, const PanelArea& a, const std::string& yLabel)
{
  const std::array<unsigned char, 3> grey{200, 200, 200}, black{40, 40, 40};
  for (double t : niceTicks(a.low, a.high, 5))
  {
    canvas.colour(grey);
    canvas.line(a.x0, a.py(t), a.x1, a.py(t));
    canvas.text(tickText(t), a.x0 - 6, static_cast<int>(a.py(t)), 12, 2, 1);
  }
  for (double t : niceTicks(0, a.xMax, 10))
  {
    if (t != std::round(t)) // frames are whole
      continue;
    canvas.colour(grey);
    canvas.line(a.px(t), a.y0, a.px(t), a.y1);
    canvas.text(tickText(t), static_cast<int>(a.px(t)), a.y0 - 6, 12, 1, 2);
  }
  canvas.colour(black);
  canvas.line(a.x0, a.y0, a.x1, a.y0);
  canvas.line(a.x0, a.y0, a.x0, a.y1);
  canvas.text("frame", (a.x0 + a.x1) / 2, a.y0 - 26, 13, 1, 2);
  canvas.text(yLabel, a.x0, a.y1 + 6, 13, 0, 0); // above the axis: no rotated text
}

// The marked frames, the lines, and the legend to the right of the panel.
void drawData(Canvas& canvas, const PanelArea& a, const PlotPanel& panel)
{
  int legendY = a.y1 - 10;
  if (!panel.marks.empty())
  {
    const std::array<unsigned char, 3> red{214, 39, 40};
    canvas.colour(red);
    for (std::size_t f : panel.marks)
      canvas.line(a.px(static_cast<double>(f)), a.y0, a.px(static_cast<double>(f)), a.y1, 1);
    canvas.line(a.x1 + 24, legendY - 8, a.x1 + 24, legendY + 8, 1);
    canvas.text(panel.marksLabel, a.x1 + 42, legendY, 12, 0, 1);
    legendY -= 22;
  }
  for (const PlotLine& l : panel.lines)
  {
    canvas.colour(l.colour);
    for (std::size_t f = 1; f < l.values.size(); ++f)
      if (std::isfinite(l.values[f - 1]) && std::isfinite(l.values[f]))
        canvas.line(a.px(static_cast<double>(f - 1)), a.py(l.values[f - 1]),
                    a.px(static_cast<double>(f)), a.py(l.values[f]), 2);
    if (l.values.size() == 1 && std::isfinite(l.values[0]))
      canvas.box(static_cast<int>(a.px(0)) - 2, static_cast<int>(a.px(0)) + 2,
                 static_cast<int>(a.py(l.values[0])) - 2, static_cast<int>(a.py(l.values[0])) + 2);
    canvas.line(a.x1 + 12, legendY, a.x1 + 36, legendY, 3);
    canvas.text(l.label, a.x1 + 42, legendY, 12, 0, 1);
    legendY -= 22;
  }
}

// The image as a PNG, beside its name and renamed when complete.
void writePng(const std::string& path, vtkImageData* image)
{
  const std::string partial = path + ".partial";
  vtkNew<vtkPNGWriter> writer;
  writer->SetInputData(image);
  writer->SetFileName(partial.c_str());
  writer->Write();
  std::error_code error;
  if (writer->GetErrorCode() != 0 || !std::filesystem::exists(partial))
    throw std::runtime_error(path + ": cannot write the plot");
  std::filesystem::rename(partial, path, error);
  if (error)
    throw std::runtime_error(path + ": " + error.message());
}

} // namespace

void writeFramePlot(const std::string& path, const std::string& title,
                    const std::vector<PlotPanel>& panels, int width, int panelHeight)
{
  const int titleHeight = 40;
  const int height = titleHeight + panelHeight * static_cast<int>(panels.size());
  Canvas canvas(width, height);
  canvas.text(title, width / 2, height - 12, 18, 1, 2, true);
  const int left = 90, right = 170, bottom = 45, top = 32;
  for (std::size_t p = 0; p < panels.size(); ++p)
  {
    const int y0 = height - titleHeight - panelHeight * static_cast<int>(p + 1) + bottom;
    const PanelArea area =
        areaOf(panels[p], left, width - right, y0, y0 + panelHeight - bottom - top);
    drawAxes(canvas, area, panels[p].yLabel);
    drawData(canvas, area, panels[p]);
  }
  writePng(path, canvas.finish());
}

} // namespace dp::cli

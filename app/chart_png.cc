#include "app/chart_png.h"

#include <vtkAxis.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPlot.h>
#include <vtkPlotPoints.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkStringArray.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>
#include <vtkWindowToImageFilter.h>

#include <cstdlib>
#include <fstream>
#include <stdexcept>

namespace fetouch::app {

bool display_available() {
  const char* display = std::getenv("DISPLAY");
  return display && *display;
}

bool window_display_available() {
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  return display_available() || (wayland && *wayland);
}

std::string no_display_hint(const std::filesystem::path& png) {
  return "no X display, so " + png.string() +
         " was not drawn (VTK draws only with a display, even offscreen); run the command under "
         "`xvfb-run -a` (Debian package xvfb) to get it";
}

void write_chart_png(const Chart& chart, const std::filesystem::path& png) {
  if (!display_available()) throw std::runtime_error(no_display_hint(png));
  {  // fail early, with the path, if the file cannot be created
    std::ofstream probe(png, std::ios::binary);
    if (!probe) throw std::runtime_error("cannot write " + png.string());
  }
  vtkNew<vtkContextView> view;
  view->GetRenderWindow()->SetOffScreenRendering(1);
  view->GetRenderWindow()->SetSize(chart.width, chart.height);
  view->GetRenderer()->SetBackground(1, 1, 1);
  vtkNew<vtkChartXY> xy;
  view->GetScene()->AddItem(xy);
  xy->SetTitle(chart.title);
  xy->GetTitleProperties()->SetFontSize(18);
  xy->GetAxis(vtkAxis::BOTTOM)->SetTitle(chart.x_label);
  xy->GetAxis(vtkAxis::LEFT)->SetTitle(chart.y_label);
  xy->GetAxis(vtkAxis::BOTTOM)->SetLogScale(chart.log_x);
  xy->GetAxis(vtkAxis::LEFT)->SetLogScale(chart.log_y);
  if (!chart.x_ticks.empty()) {
    vtkNew<vtkDoubleArray> positions;
    vtkNew<vtkStringArray> labels;
    for (std::size_t i = 0; i < chart.x_ticks.size(); ++i) {
      positions->InsertNextValue(static_cast<double>(i));
      labels->InsertNextValue(chart.x_ticks[i]);
    }
    vtkAxis* bottom = xy->GetAxis(vtkAxis::BOTTOM);
    bottom->SetCustomTickPositions(positions, labels);
    bottom->SetRange(-0.6, static_cast<double>(chart.x_ticks.size()) - 0.4);
    bottom->SetBehavior(vtkAxis::FIXED);
  }
  xy->SetShowLegend(true);
  xy->GetLegend()->SetHorizontalAlignment(vtkChartLegend::RIGHT);
  xy->GetLegend()->SetVerticalAlignment(vtkChartLegend::TOP);
  for (const ChartSeries& s : chart.series) {
    if (s.x.size() != s.y.size()) throw std::invalid_argument("chart series " + s.name + ": x and y differ in length");
    if (s.x.empty()) continue;
    vtkNew<vtkTable> table;
    vtkNew<vtkDoubleArray> x, y;
    x->SetName((s.name + " x").c_str());
    y->SetName(s.name.c_str());
    for (size_t i = 0; i < s.x.size(); ++i) {
      x->InsertNextValue(s.x[i]);
      y->InsertNextValue(s.y[i]);
    }
    table->AddColumn(x);
    table->AddColumn(y);
    vtkPlot* plot = xy->AddPlot(s.bars ? vtkChart::BAR : s.points ? vtkChart::POINTS : vtkChart::LINE);
    plot->SetInputData(table, 0, 1);
    plot->SetColor(s.color[0], s.color[1], s.color[2], 255);
    plot->SetWidth(s.width);
    plot->SetLabel(s.name);
    if (auto* points = vtkPlotPoints::SafeDownCast(plot)) {
      points->SetMarkerStyle(vtkPlotPoints::CIRCLE);
      points->SetMarkerSize(s.width);
    }
  }
  view->GetRenderWindow()->Render();
  vtkNew<vtkWindowToImageFilter> image;
  image->SetInput(view->GetRenderWindow());
  image->ReadFrontBufferOff();
  image->Update();
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(png.string().c_str());
  writer->SetInputConnection(image->GetOutputPort());
  writer->Write();
  if (writer->GetErrorCode() != 0) throw std::runtime_error("cannot write " + png.string());
}

}  // namespace fetouch::app

// `fetouch render`: a picture (PNG, drawn offscreen by VTK) of a tetrahedral mesh — its outer
// surface with the element edges — or of a volume's middle slice, for reports and the docs.
#include <CLI/CLI.hpp>
#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellData.h>
#include <vtkDataSetSurfaceFilter.h>
#include <vtkFloatArray.h>
#include <vtkImageActor.h>
#include <vtkImageMapper3D.h>
#include <vtkImageData.h>
#include <vtkImageMapToColors.h>
#include <vtkImageProperty.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkThreshold.h>
#include <vtkUnstructuredGrid.h>
#include <vtkWindowToImageFilter.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "app/chart_png.h"
#include "app/cli.h"
#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "meshes/mesh_file_checks.h"
#include "imaging/volume_io.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;

struct RenderOptions {
  std::string input, out = "render.png", title;
  int width = 900, height = 700;
  double azimuth = 30, elevation = 20;
  bool labels = false;  // a label map: colours per label
};

void add_title(vtkRenderer* renderer, const std::string& text) {
  vtkNew<vtkTextActor> title;
  title->SetInput(text.c_str());
  title->GetTextProperty()->SetFontSize(20);
  title->GetTextProperty()->SetColor(0.1, 0.1, 0.1);
  title->SetDisplayPosition(12, 12);
  renderer->AddViewProp(title);
}

void write_png(vtkRenderer* renderer, const RenderOptions& o) {
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetSize(o.width, o.height);
  window->AddRenderer(renderer);
  window->Render();
  vtkNew<vtkWindowToImageFilter> image;
  image->SetInput(window);
  image->ReadFrontBufferOff();
  image->Update();
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(o.out.c_str());
  writer->SetInputConnection(image->GetOutputPort());
  writer->Write();
  if (writer->GetErrorCode() != 0 || !fs::exists(o.out)) throw std::runtime_error(o.out + ": could not be written");
}

// The outer surface of the tetrahedra (boundary triangles stored beside them left out), shaded,
// with the element edges.
void render_mesh(const RenderOptions& o, vtkRenderer* renderer, std::string* caption) {
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  meshes::check_mesh_file(o.input);  // a regular file whose declared sizes fit the memory budget
  if (!reader->CanReadFile(o.input.c_str())) throw std::runtime_error(o.input + ": not a VTK unstructured grid (.vtu)");
  reader->SetFileName(o.input.c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  vtkNew<vtkUnstructuredGrid> tets;
  tets->SetPoints(grid->GetPoints());
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
    if (grid->GetCellType(c) == VTK_TETRA || grid->GetCellType(c) == VTK_HEXAHEDRON) {
      vtkNew<vtkIdList> ids;
      grid->GetCellPoints(c, ids);
      tets->InsertNextCell(grid->GetCellType(c), ids);
    }
  if (tets->GetNumberOfCells() == 0) throw std::runtime_error(o.input + ": no tetrahedra or hexahedra to draw");
  vtkNew<vtkDataSetSurfaceFilter> surface;
  surface->SetInputData(tets);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputConnection(surface->GetOutputPort());
  mapper->ScalarVisibilityOff();
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(0.93, 0.66, 0.60);
  actor->GetProperty()->EdgeVisibilityOn();
  actor->GetProperty()->SetEdgeColor(0.35, 0.2, 0.2);
  actor->GetProperty()->SetSpecular(0.2);
  renderer->AddActor(actor);
  renderer->ResetCamera();
  renderer->GetActiveCamera()->Azimuth(o.azimuth);
  renderer->GetActiveCamera()->Elevation(o.elevation);
  renderer->GetActiveCamera()->OrthogonalizeViewUp();
  renderer->ResetCamera();
  double b[6];
  tets->GetBounds(b);
  std::ostringstream text;
  text.precision(3);
  text << tets->GetNumberOfCells() << " elements, " << (b[1] - b[0]) * 1e3 << " x " << (b[3] - b[2]) * 1e3 << " x "
       << (b[5] - b[4]) * 1e3 << " mm";
  *caption = text.str();
}

// The slice through the middle of the volume across its second axis (x to the right, z up: the
// beams of an ultrasound volume run down), in grey levels from its 1st to 99th percentile, or in
// one colour per label.
void render_slice(const RenderOptions& o, vtkRenderer* renderer, std::string* caption) {
  const imaging::Volume<float> v = imaging::read_volume(o.input);
  const int nx = v.dimensions[0], nz = v.dimensions[2], j = v.dimensions[1] / 2;
  vtkNew<vtkImageData> slice;
  slice->SetDimensions(nx, nz, 1);
  slice->SetSpacing(v.spacing_mm[0], v.spacing_mm[2], 1);
  vtkNew<vtkFloatArray> values;
  values->SetNumberOfTuples(vtkIdType(nx) * nz);
  std::vector<float> all;
  for (int k = 0; k < nz; ++k)
    for (int i = 0; i < nx; ++i) {
      const float x = v.data[v.index(i, j, k)];
      values->SetValue(vtkIdType(k) * nx + i, x);
      all.push_back(x);
    }
  slice->GetPointData()->SetScalars(values);
  std::sort(all.begin(), all.end());
  vtkNew<vtkLookupTable> colours;
  if (o.labels) {
    const int top = std::max(1, static_cast<int>(all.back()));
    colours->SetNumberOfTableValues(top + 1);
    colours->SetTableRange(0, top);
    const double palette[8][3] = {{0.15, 0.15, 0.15}, {0.80, 0.45, 0.45}, {0.35, 0.55, 0.85}, {0.95, 0.85, 0.55},
                                  {0.95, 0.95, 0.95}, {0.55, 0.80, 0.45}, {0.75, 0.55, 0.85}, {0.9, 0.6, 0.2}};
    for (int l = 0; l <= top; ++l) colours->SetTableValue(l, palette[l % 8][0], palette[l % 8][1], palette[l % 8][2]);
  } else {
    const float lo = all[all.size() / 100], hi = std::max(lo + 1e-6f, all[all.size() * 99 / 100]);
    colours->SetTableRange(lo, hi);
    colours->SetSaturationRange(0, 0);
    colours->SetHueRange(0, 0);
    colours->SetValueRange(0, 1);
  }
  colours->Build();
  vtkNew<vtkImageMapToColors> mapped;
  mapped->SetInputData(slice);
  mapped->SetLookupTable(colours);
  vtkNew<vtkImageActor> actor;
  actor->GetMapper()->SetInputConnection(mapped->GetOutputPort());
  actor->GetProperty()->SetInterpolationTypeToNearest();
  renderer->AddActor(actor);
  renderer->GetActiveCamera()->ParallelProjectionOn();
  renderer->ResetCamera();
  renderer->GetActiveCamera()->Zoom(1.35);
  std::ostringstream text;
  text.precision(3);
  text << "slice y = " << v.position_mm(0, j, 0)[1] << " mm of " << nx << " x " << v.dimensions[1] << " x " << nz
       << " voxels (" << v.spacing_mm[0] << " mm)";
  *caption = text.str();
}

int run_render(const RenderOptions& o) {
  if (fs::path(o.out).extension() != ".png") {
    std::cerr << "error: --out must end in .png: " << o.out << "\n";
    return kExitBadInput;
  }
  if (!display_available()) {
    std::cerr << "error: " << no_display_hint(o.out) << "\n";
    return kExitFailure;
  }
  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(1, 1, 1);
  std::string caption;
  try {
    if (fs::path(o.input).extension() == ".vtu")
      render_mesh(o, renderer, &caption);
    else
      render_slice(o, renderer, &caption);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  }
  add_title(renderer, o.title.empty() ? caption : o.title + " — " + caption);
  try {
    if (fs::path(o.out).has_parent_path()) fs::create_directories(fs::path(o.out).parent_path());
    write_png(renderer, o);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitFailure;
  }
  std::cout << "wrote " << o.out << "\n";
  return kExitOk;
}

}  // namespace

void add_render_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* cmd = parent.add_subcommand("render", drawing_command_description("render"));
  cmd->footer(
      "A .vtu mesh is drawn as the outer surface of its elements with their edges; a volume (.mha,\n"
      ".mhd, .vti, .nrrd, a DICOM folder) as its middle slice across y, in grey levels (or colours per\n"
      "label with --labels). Drawn offscreen by VTK, which needs an X display: run under xvfb-run -a\n"
      "on a headless machine. Example: fetouch render fetus.vtu --out fetus.png");
  cmd->add_option("input", o->input, "A .vtu mesh or a volume")->required()->check(CLI::ExistingPath);
  cmd->add_option("--out", o->out, "The PNG to write")->capture_default_str();
  cmd->add_option("--title", o->title, "A title before the caption");
  cmd->add_option("--width", o->width, "Width, pixels")->check(CLI::Range(64, 4096))->capture_default_str();
  cmd->add_option("--height", o->height, "Height, pixels")->check(CLI::Range(64, 4096))->capture_default_str();
  cmd->add_option("--azimuth", o->azimuth, "Camera turn about the vertical, degrees (meshes)")->capture_default_str();
  cmd->add_option("--elevation", o->elevation, "Camera tilt, degrees (meshes)")->capture_default_str();
  cmd->add_flag("--labels", o->labels, "The volume is a label map: one colour per label");
  cmd->callback([o, &exit_code]() { exit_code = run_render(*o); });
}

}  // namespace fetouch::app

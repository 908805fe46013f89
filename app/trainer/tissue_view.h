// The trainer's 3D view (VTK, no Qt): the deformed tissue's surface coloured by displacement
// magnitude or von Mises stress with a colour bar, the outer wall see-through where the scene has
// inner structures (their interfaces drawn opaque, region by region, each one shown or hidden;
// every surface shaded with point normals, split where it folds by over 60 degrees), and per probe the tool at the device point, its
// proxy on the surface and its force as an arrow; the mouse cursor when the mouse drives a probe.
#pragma once

#include <Eigen/Core>
#include <vtkSmartPointer.h>

#include <array>
#include <string>
#include <vector>

#include "app/session.h"
#include "app/trainer/label_surfaces.h"
#include "app/trainer/trainer_session.h"

class vtkRenderer;
class vtkPolyData;
class vtkPoints;
class vtkFloatArray;
class vtkPolyDataMapper;
class vtkActor;
class vtkScalarBarActor;
class vtkLookupTable;
class vtkPolyDataNormals;

namespace fetouch::app::trainer {

// What colours the surfaces: the displacement's magnitude, the von Mises stress (both on a colour
// bar), or each region its own colour (the wall skin-toned: the anatomy, as the review and the
// exercise's answer show it).
enum class ColourField { displacement, von_mises, regions };

class TissueView {
 public:
  // With `smooth` (label_surfaces.h), the regions draw those surfaces, carried by the mesh's
  // displacement, instead of the element faces between regions.
  TissueView(vtkRenderer* renderer, const MeshView& mesh, const std::vector<double>& probe_radii_m,
             std::vector<LabelSurface> smooth = {});
  ~TissueView();
  // The tissue as the snapshot has it.
  void update_tissue(const TissueSnapshot& snapshot, ColourField field);
  // The probes as the newest tick has them (the first `count`).
  void update_probes(const std::array<SessionMonitor::ProbeTick, SessionMonitor::kMaxDevices>& probes, int count);
  void show_cursor(bool on, const Eigen::Vector3d& at = Eigen::Vector3d::Zero());
  void reset_camera();
  void show_colour_bar(bool on);  // the colour field's bar (shown unless hidden here)
  bool has_inner_structures() const { return interfaces_ > 0; }
  // The colour of region i when the field is `regions` (r, g, b in 0..1).
  std::array<double, 3> region_colour(std::size_t i) const;

  // The regions that draw interfaces: each draws the faces it shares with a larger region (the
  // one around it), oriented out of it.
  std::size_t regions() const { return layers_.size(); }
  const std::string& region_name(std::size_t i) const { return layers_[i].name; }
  void set_region_visible(std::size_t i, bool on);
  bool region_visible(std::size_t i) const;
  // What region i draws: its points at rest (the mesh's nodes, or a smooth surface's own), its
  // triangles (indices into them) and the material across each, and the polydata as drawn
  // (deformed points, split normals).
  bool draws_label_surfaces() const { return embedded_; }
  const std::vector<std::array<double, 3>>& region_points(std::size_t i) const {
    return layers_[i].embedded.points.empty() ? mesh_.points : layers_[i].embedded.points;
  }
  const std::vector<std::array<unsigned int, 3>>& region_triangles(std::size_t i) const { return layers_[i].triangles; }
  const std::vector<unsigned int>& region_across(std::size_t i) const { return layers_[i].across; }
  vtkPolyData* drawn_region(std::size_t i);

 private:
  struct ProbeActors {
    vtkSmartPointer<vtkActor> tool, proxy, arrow;
  };
  struct RegionLayer {
    std::string name;
    unsigned int material = 0;
    std::vector<std::array<unsigned int, 3>> triangles;
    std::vector<unsigned int> across, cells;  // per triangle: the material across, the solver's cell
    LabelSurface embedded;                    // a smooth surface's points and their tetrahedra (or none)
    vtkSmartPointer<vtkPoints> points;        // its deformed points (else the mesh's, shared)
    vtkSmartPointer<vtkFloatArray> magnitude;
    vtkSmartPointer<vtkPolyData> data;
    vtkSmartPointer<vtkFloatArray> stress;
    vtkSmartPointer<vtkPolyDataNormals> normals;
    vtkSmartPointer<vtkPolyDataMapper> mapper;
    vtkSmartPointer<vtkActor> actor;
  };
  vtkRenderer* renderer_;
  const MeshView& mesh_;
  vtkSmartPointer<vtkPoints> points_;
  vtkSmartPointer<vtkPolyData> surface_;
  vtkSmartPointer<vtkPolyDataNormals> surface_normals_;
  vtkSmartPointer<vtkFloatArray> magnitude_, stress_;
  vtkSmartPointer<vtkPolyDataMapper> surface_mapper_;
  vtkSmartPointer<vtkLookupTable> lookup_;
  vtkSmartPointer<vtkScalarBarActor> bar_;
  vtkSmartPointer<vtkActor> surface_actor_, cursor_;
  std::vector<RegionLayer> layers_;
  std::vector<ProbeActors> probes_;
  std::size_t interfaces_ = 0;
  bool embedded_ = false;
  ColourField field_ = ColourField::displacement;
  bool bar_wanted_ = true;
};

}  // namespace fetouch::app::trainer

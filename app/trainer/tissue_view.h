// The trainer's 3D view (VTK, no Qt): the deformed tissue's surface coloured by displacement
// magnitude or von Mises stress with a colour bar, the outer wall see-through where the scene has
// inner structures (their interfaces drawn opaque), and per probe the tool at the device point, its
// proxy on the surface and its force as an arrow; the mouse cursor when the mouse drives a probe.
#pragma once

#include <Eigen/Core>
#include <vtkSmartPointer.h>

#include <array>
#include <vector>

#include "app/session.h"
#include "app/trainer/trainer_session.h"

class vtkRenderer;
class vtkPolyData;
class vtkPoints;
class vtkFloatArray;
class vtkPolyDataMapper;
class vtkActor;
class vtkScalarBarActor;
class vtkLookupTable;

namespace fetouch::app::trainer {

enum class ColourField { displacement, von_mises };

class TissueView {
 public:
  TissueView(vtkRenderer* renderer, const MeshView& mesh, const std::vector<double>& probe_radii_m);
  ~TissueView();
  // The tissue as the snapshot has it.
  void update_tissue(const TissueSnapshot& snapshot, ColourField field);
  // The probes as the newest tick has them (the first `count`).
  void update_probes(const std::array<SessionMonitor::ProbeTick, SessionMonitor::kMaxDevices>& probes, int count);
  void show_cursor(bool on, const Eigen::Vector3d& at = Eigen::Vector3d::Zero());
  void reset_camera();
  bool has_inner_structures() const { return interfaces_ > 0; }

 private:
  struct ProbeActors {
    vtkSmartPointer<vtkActor> tool, proxy, arrow;
  };
  vtkRenderer* renderer_;
  const MeshView& mesh_;
  vtkSmartPointer<vtkPoints> points_;
  vtkSmartPointer<vtkPolyData> surface_, inner_;
  vtkSmartPointer<vtkFloatArray> magnitude_, stress_;
  vtkSmartPointer<vtkPolyDataMapper> surface_mapper_, inner_mapper_;
  vtkSmartPointer<vtkLookupTable> lookup_;
  vtkSmartPointer<vtkScalarBarActor> bar_;
  vtkSmartPointer<vtkActor> surface_actor_, inner_actor_, cursor_;
  std::vector<unsigned int> triangle_cell_;  // the cell of each drawn triangle (outer, then inner)
  std::vector<ProbeActors> probes_;
  std::size_t interfaces_ = 0;
  ColourField field_ = ColourField::displacement;
};

}  // namespace fetouch::app::trainer

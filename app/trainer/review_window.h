// `fetouch review`'s window (Qt 5 + VTK 9): a recorded take played back over the anatomy it was
// made on. The trainee's probe paths are drawn over the anatomy (pressing: coloured by the force,
// green to red; moving between presses: thin grey), each probe's tool, contact point and force at
// the time chosen on a slider (scrub, or play at the take's pace), the forces against time with the
// maneuvers and the comfort limit marked, and the exercise's scores with its coverage map when the
// take is an exercise's (docs/trainer.md, "Reviewing a take").
//
// An exercise's take is seen from the front with the fundus up and the mother's right on the left,
// as its coverage map is drawn; any other take from the trainer's default camera.
//
// A take is a folder: a recording (take.h5, app/recording.h) and the mesh it was made on
// (anatomy.vtu, or STEM.anatomy.vtu beside STEM.h5: view_export.h), which `fetouch trainer` writes
// beside every take it records; the exercise's assessment.json and coverage.png beside them when there are.
#pragma once

#include <QMainWindow>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/recording.h"
#include "app/trainer/label_surfaces.h"
#include "app/trainer/tissue_view.h"

class QLabel;
class QPushButton;
class QSlider;
class QTimer;
class QVTKOpenGLNativeWidget;
class vtkActor;
class vtkCamera;
class vtkGenericOpenGLRenderWindow;
class vtkRenderer;
class vtkScalarBarActor;

namespace fetouch::app::trainer {

// The exercise's scores as assessment.json has them (what the review shows of them).
struct ReviewScores {
  std::string pose;
  struct Answer {
    std::string asked, given, truth;
    double score = 0;
  };
  std::vector<Answer> answers;
  struct Maneuver {
    std::string name;
    double start_s = 0, end_s = 0, largest_force_n = 0;
    bool reached = false;
  };
  std::vector<Maneuver> maneuvers;
  double duration_s = 0, largest_force_n = 0, comfort_limit_n = 0, time_over_limit_s = 0, covered_share = 0;
  std::string comfort_limit_source;
  double answer_score() const {  // the answers' scores summed, as Assessment::answer_score
    double sum = 0;
    for (const Answer& a : answers) sum += a.score;
    return sum;
  }
};

struct ReviewTake {
  std::filesystem::path dir, recording_file, anatomy_file;
  Recording recording;
  MeshView anatomy;
  std::vector<double> probe_radii_m;     // from the recorded scene (5 mm each where it cannot be read)
  // The regions' smooth surfaces over voted regions (label_surfaces.h), from the recorded scene;
  // none where it has none or cannot be read (the mesh's faces are drawn then).
  std::vector<LabelSurface> smooth;
  std::optional<ReviewScores> scores;    // the exercise's, when DIR has assessment.json
  std::filesystem::path coverage_png;    // empty: none
  double duration_s = 0;
};

// Reads DIR (a take folder; `recording` names another .h5 than DIR/take.h5, relative to DIR).
// Throws std::runtime_error naming the file and what is wrong.
ReviewTake load_review_take(const std::filesystem::path& dir, const std::filesystem::path& recording = {});

struct ReviewOptions {
  double at_s = -1;        // the time shown first (-1: the take's end)
  bool paths = true;       // draw the probe paths
};

class ReviewWindow : public QMainWindow {
 public:
  ReviewWindow(ReviewTake take, const ReviewOptions& options);
  ~ReviewWindow() override;
  // Shows the take at time t (clamped to the take), as the slider does.
  void show_time(double t_s);
  double time_shown() const { return time_s_; }
  void set_paths_visible(bool on);
  bool save_screenshot(const std::filesystem::path& file);
  const ReviewTake& take() const { return take_; }
  // The 3D view's camera, and the view's place in the window's screenshot (pixels, from the top left).
  vtkCamera* camera() const;
  struct Rect {
    int x = 0, y = 0, width = 0, height = 0;
  };
  Rect view_rect() const;
  double path_force_range_n() const { return force_range_n_; }  // red at this force (green at 0)
  // The maneuver at time t (-1: none, or not an exercise).
  int maneuver_at(double t_s) const;

 private:
  void build_paths();
  void toggle_play();
  void step_play();
  std::size_t sample_at(std::size_t device, double t_s) const;

  ReviewTake take_;
  ReviewOptions options_;
  std::unique_ptr<TissueView> view_;
  QVTKOpenGLNativeWidget* vtk_widget_ = nullptr;
  vtkGenericOpenGLRenderWindow* render_window_ = nullptr;
  vtkRenderer *renderer_ = nullptr, *travel_layer_ = nullptr, *press_layer_ = nullptr;
  std::vector<vtkActor*> path_actors_;  // held by their layers
  vtkSmartPointer<vtkScalarBarActor> bar_;
  QSlider* slider_ = nullptr;
  QLabel *time_label_ = nullptr, *scores_ = nullptr, *coverage_ = nullptr;
  QWidget* plot_ = nullptr;
  QPushButton* play_ = nullptr;
  QTimer* player_ = nullptr;
  double time_s_ = 0, force_range_n_ = 1;
  std::chrono::steady_clock::time_point play_from_;
  double play_from_s_ = 0;
};

}  // namespace fetouch::app::trainer

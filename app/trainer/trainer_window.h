// `fetouch trainer`'s window (Qt 5 + VTK 9): the 3D view of the tissue as solved, the ultrasound
// image through the deformed tissue, force and frame-time plots, a status line, and the controls
// (docs/trainer.md lists each with its shortcut). The window owns a TrainerSession and reads it
// through lock-free hand-overs on a 30 ms timer: it never blocks the haptic or solver threads.
#pragma once

#include <QMainWindow>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/trainer/deformed_slice.h"
#include "app/trainer/tissue_view.h"
#include "app/trainer/trainer_session.h"

class QComboBox;
class QLabel;
class QTimer;
class QVTKOpenGLNativeWidget;
class vtkGenericOpenGLRenderWindow;
class vtkRenderer;

namespace fetouch::app::trainer {

class TracePlot;

struct WindowOptions {
  std::filesystem::path out = "fetouch-trainer";  // takes and screenshots go here
  std::optional<std::filesystem::path> screenshot;  // headless: written when the session ends
  bool headless = false;                             // close once the session has ended
};

// What the window measured, for the command's summary.
struct WindowFigures {
  long ultrasound_images = 0;
  double ultrasound_seconds = 0;  // time spent making them
  double wall_s = 0;
  long renders = 0;
  std::string error;
  // Beside --screenshot OUT.png: OUT.ultrasound.png, the ultrasound image of the tissue shown at the
  // end (`frame`), in `plane`, the volume scaled by `gain` (none: the cross-section), and OUT.vtu,
  // that tissue (view_export.h).
  std::filesystem::path ultrasound_png, tissue_vtu;
  SlicePlane plane;
  double gain = 1;
  bool volume = false;
  long frame = -1;
};

class TrainerWindow : public QMainWindow {
 public:
  TrainerWindow(const config::Scene& scene, const TrainerOptions& session, const WindowOptions& window,
                std::filesystem::path scene_path = {});
  ~TrainerWindow() override;
  const WindowFigures& figures() const { return figures_; }
  TrainerSession* session() { return session_.get(); }
  bool save_screenshot(const std::filesystem::path& file);
  // The controls, as the buttons and shortcuts call them (tests call them too).
  // Open: another scene, checked whole first; refused (false, the reason on the message line) if
  // it cannot be loaded, and the running session goes on.
  bool open_scene(const std::filesystem::path& file);
  void toggle_pause();
  void reset();
  void toggle_recording();
  void toggle_colour_field();
  void toggle_plane();
  void reset_camera();
  // Asks the session for another local model and hold; the answer comes on the message line
  // (applied, or refused with the reason) within a frame or two.
  void ask_mode(haptics::LocalModelKind model, haptics::HoldKind hold);
  haptics::LocalModelKind local_model() const { return model_; }  // the mode in force, as last answered
  haptics::HoldKind hold() const { return hold_; }
  std::string message() const;  // the message line
  void move_cursor_along_view(double metres);
  const std::vector<std::uint8_t>& ultrasound_image() const { return image_; }
  const std::vector<float>& ultrasound_reference() const { return reference_; }
  const SlicePlane& ultrasound_plane() const { return plane_; }
  std::optional<std::filesystem::path> recording() const { return recording_; }
  const TissueSnapshot& shown() const { return shown_; }  // the tissue state on screen
  const Eigen::Vector3d& cursor() const { return cursor_; }
  void set_cursor(const Eigen::Vector3d& at);  // the mouse cursor's place (a mouse probe follows it)

 protected:
  bool eventFilter(QObject* watched, QEvent* event) override;

 private:
  void start_take(const std::optional<std::filesystem::path>& recording);
  void tick();
  void update_ultrasound(const Eigen::Vector3d& point, const Eigen::Vector3d& normal);
  void update_status();
  void take_mode_verdict();
  void show_mode();
  void set_cursor_at_display(double x, double y);
  void export_views(const std::filesystem::path& screenshot);

  config::Scene scene_;
  TrainerOptions session_options_;
  WindowOptions window_options_;
  std::unique_ptr<TrainerSession> session_;
  std::unique_ptr<TissueView> view_;
  std::unique_ptr<DeformedSlicer> slicer_;
  ReferenceVolume volume_;
  double gain_ = 1;
  std::string volume_description_;
  QVTKOpenGLNativeWidget* vtk_widget_ = nullptr;
  vtkGenericOpenGLRenderWindow* render_window_ = nullptr;
  vtkRenderer* renderer_ = nullptr;
  QLabel *ultrasound_ = nullptr, *status_ = nullptr, *message_ = nullptr;
  TracePlot *force_plot_ = nullptr, *frame_plot_ = nullptr, *margin_plot_ = nullptr;
  std::filesystem::path scene_path_;
  QTimer* timer_ = nullptr;
  QComboBox *model_box_ = nullptr, *hold_box_ = nullptr;
  haptics::LocalModelKind model_ = haptics::LocalModelKind::pi;
  haptics::HoldKind hold_ = haptics::HoldKind::zoh;
  haptics::LocalModelKind asked_model_ = haptics::LocalModelKind::pi;  // the newest asked (the mode in force when
  haptics::HoldKind asked_hold_ = haptics::HoldKind::zoh;              // none is pending)
  long mode_request_ = 0;  // the newest asked of this take's session (0: none)
  ColourField field_ = ColourField::displacement;
  bool lateral_x_ = true;
  Eigen::Vector3d cursor_ = Eigen::Vector3d::Zero();
  std::vector<std::uint8_t> image_;
  std::vector<float> reference_;
  SlicePlane plane_;
  std::optional<std::filesystem::path> recording_;
  int takes_ = 0, screenshots_ = 0;
  long last_frame_ = -2, frames_seen_ = 0, overruns_ = 0, imaged_frame_ = -3;
  Eigen::Vector3d imaged_at_ = Eigen::Vector3d::Zero();  // where the shown image's plane went through
  double haptic_hz_ = 0, solver_hz_ = 0, ultrasound_hz_ = 0;
  std::chrono::steady_clock::time_point started_, rate_from_;
  long rate_ticks_ = 0, rate_frames_ = 0, rate_images_ = 0;
  WindowFigures figures_;
  TissueSnapshot shown_;
};

}  // namespace fetouch::app::trainer

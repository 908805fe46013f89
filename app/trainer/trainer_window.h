// `fetouch trainer`'s window (Qt 5 + VTK 9): the 3D view of the tissue as solved, the ultrasound
// image through the deformed tissue, force and frame-time plots, a status line, and the controls
// (docs/trainer.md lists each with its shortcut). The window owns a TrainerSession and reads it
// through lock-free hand-overs on a 20 ms timer: it never blocks the haptic or solver threads.
#pragma once

#include <QMainWindow>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "app/exercise/leopold.h"
#include "app/machine_load.h"
#include "app/trainer/deformed_slice.h"
#include "app/trainer/tissue_view.h"
#include "app/trainer/trainer_session.h"
#include "app/trainer/ultrasound_imager.h"

class QComboBox;
class QPushButton;
class QToolBar;
class QLabel;
class QTimer;
class QVTKOpenGLStereoWidget;
class vtkGenericOpenGLRenderWindow;
class vtkRenderer;

namespace fetouch::app::trainer {

class TracePlot;
class ReviewWindow;

// The Leopold exercise (docs/trainer.md): the four maneuvers guided one by one with the fetus and
// the ultrasound hidden, then the answers, then the assessment (app/exercise/leopold.h) written to
// OUT/exercise and the fetus shown. The scene is a phantom scene whose pose the command has drawn.
struct ExerciseOptions {
  bool on = false;
  // Scripted (tests, demonstrations): the simulated times at which maneuvers 2, 3 and 4 begin, and
  // the answers given when the take ends.
  std::optional<std::array<double, exercise::kManeuvers - 1>> maneuver_times;
  std::optional<exercise::Answers> answers;
  double comfort_limit_n = 0;  // 0: none stated
  std::string comfort_limit_source;
  // Pictures of each step (docs, tests): DIR/step-K.png 1.7 s (simulated) into maneuver K, when a
  // scripted hand holds its first press; DIR/answers.png with the answers chosen, before they are given.
  std::optional<std::filesystem::path> step_screenshots;
};

struct WindowOptions {
  std::filesystem::path out = "fetouch-trainer";  // takes and screenshots go here
  std::optional<std::filesystem::path> screenshot;  // headless: written when the session ends
  bool headless = false;                             // close once the session has ended
  ExerciseOptions exercise;
};

// Other programs keeping this much of the machine busy (cores) make the status line say so: the
// window and the ultrasound then slow down, the solver does not (app/realtime_cores.h).
inline constexpr double kBusyCores = 0.5;

// What the window measured, for the command's summary.
struct WindowFigures {
  long ultrasound_asked = 0;      // images asked for (a new frame, or the probe moved)
  long ultrasound_images = 0;     // shown (an image asked for is skipped if a newer one is asked before it starts)
  double ultrasound_seconds = 0;  // time spent making those (on the imager's thread)
  double ultrasound_per_s = 0;    // shown per second of the last take, from its start to its end
  double wall_s = 0;
  long renders = 0;
  double render_seconds = 0;  // spent rendering the 3D view (its surfaces' normals included)
  double renders_per_s = 0;   // of the last take, as ultrasound_per_s
  // Other programs' use of the CPU, measured each second (app/machine_load.h): the most, in cores,
  // and the seconds in which it reached kBusyCores (the status line then says so).
  double others_cores_max = 0;
  double busy_s = 0;
  std::string error;
  // Beside --screenshot OUT.png: OUT.ultrasound.png, the ultrasound image of the tissue shown at the
  // end (`frame`), in `plane`, the volume scaled by `gain` (none: the cross-section), and OUT.vtu,
  // that tissue (view_export.h).
  std::filesystem::path ultrasound_png, tissue_vtu;
  std::optional<exercise::Assessment> assessment;  // the exercise's, once answered
  std::filesystem::path assessment_dir;
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
  std::string status() const;   // the status line (rates, gains, passivity, felt stiffness)
  void move_cursor_along_view(double metres);
  const UltrasoundImage& ultrasound_image() const { return image_; }  // the one shown
  std::optional<std::filesystem::path> recording() const { return recording_; }
  const TissueSnapshot& shown() const { return shown_; }  // the tissue state on screen
  const Eigen::Vector3d& cursor() const { return cursor_; }
  void set_cursor(const Eigen::Vector3d& at);  // the mouse cursor's place (a mouse probe follows it)
  // The mouse on to the next probe it drives (Tab), the one it leaves holding where it is; false
  // (the reason on the message line) when it drives one probe or none.
  bool switch_hand();
  // The 3D view (null while no session runs) and the toolbar's region toggles: hiding a region shows
  // what its surfaces covered; kept across takes and scenes by name. False: no such region.
  TissueView* view() { return view_.get(); }
  bool set_region_visible(const std::string& name, bool on);
  // The exercise (trainer_exercise.cc): the next maneuver (N), or the answers after the fourth;
  // answering ends the take, assesses it and shows the fetus. False (the reason on the message
  // line) when it is not the time for it.
  bool next_maneuver();
  bool answer(const exercise::Answers& answers);
  int exercise_step() const { return step_; }  // 0..3 the maneuvers, 4 the answers, 5 assessed
  // The assessed take in `fetouch review`'s window, beside this one (null, the reason on the
  // message line, before the exercise is assessed or if the take cannot be read).
  ReviewWindow* open_review();

 protected:
  bool eventFilter(QObject* watched, QEvent* event) override;

 private:
  void start_take(const std::optional<std::filesystem::path>& recording);
  void tick();
  void show_ultrasound();
  bool view_due() const;  // whether this tick renders the 3D view
  void image_now();  // the ultrasound image through the first probe's patch, made here and shown
  void update_status();
  void take_mode_verdict();
  void show_mode();
  void set_cursor_at_display(double x, double y);
  void export_views(const std::filesystem::path& screenshot);
  QWidget* build_exercise_panel();
  void show_exercise_step();
  void exercise_tick();
  void picture_step(const std::string& name);
  void choose_answers(const exercise::Answers& given);
  void hide_the_answer(bool hidden);
  double simulated_s();

  config::Scene scene_;
  TrainerOptions session_options_;
  WindowOptions window_options_;
  std::unique_ptr<TrainerSession> session_;
  std::unique_ptr<TissueView> view_;
  // The smooth surfaces the regions draw (label_surfaces.h), made once per scene and mesh.
  LabelSurfaceCache smooth_;
  std::unique_ptr<UltrasoundImager> imager_;
  std::shared_ptr<const ReferenceVolume> volume_;
  double gain_ = 1;
  std::string volume_description_;
  QVTKOpenGLStereoWidget* vtk_widget_ = nullptr;
  vtkGenericOpenGLRenderWindow* render_window_ = nullptr;
  vtkRenderer* renderer_ = nullptr;
  QLabel *ultrasound_ = nullptr, *status_ = nullptr, *message_ = nullptr;
  TracePlot *force_plot_ = nullptr, *frame_plot_ = nullptr, *margin_plot_ = nullptr, *energy_plot_ = nullptr;
  // Each probe's last published tick (passivity and identification figures for the status line).
  std::array<SessionMonitor::ProbeTick, SessionMonitor::kMaxDevices> last_probes_{};
  std::filesystem::path scene_path_;
  QTimer* timer_ = nullptr;
  QComboBox *model_box_ = nullptr, *hold_box_ = nullptr;
  QToolBar* regions_bar_ = nullptr;
  std::set<std::string> hidden_regions_;
  haptics::LocalModelKind model_ = haptics::LocalModelKind::pi;
  haptics::HoldKind hold_ = haptics::HoldKind::zoh;
  haptics::LocalModelKind asked_model_ = haptics::LocalModelKind::pi;  // the newest asked (the mode in force when
  haptics::HoldKind asked_hold_ = haptics::HoldKind::zoh;              // none is pending)
  long mode_request_ = 0;  // the newest asked of this take's session (0: none)
  ColourField field_ = ColourField::displacement;
  bool start_pending_ = false;  // the take's session starts at the next tick
  bool lateral_x_ = true;
  Eigen::Vector3d cursor_ = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> cursor_targets_;  // per probe: where the mouse left its cursor
  UltrasoundImage image_;  // the one shown
  SlicePlane plane_;       // the newest asked for
  std::optional<std::filesystem::path> recording_;
  int takes_ = 0, screenshots_ = 0;
  long last_frame_ = -2, overruns_ = 0, imaged_frame_ = -3;
  Eigen::Vector3d imaged_at_ = Eigen::Vector3d::Zero();  // where the shown image's plane went through
  double haptic_hz_ = 0, solver_hz_ = 0, ultrasound_hz_ = 0, view_hz_ = 0, others_cores_ = 0;
  CpuSample cpu_;
  std::chrono::steady_clock::time_point rendered_at_{};  // the last render of the 3D view began
  double render_s_ = 0;                                  // and took this long
  long rate_renders_ = 0;
  std::chrono::steady_clock::time_point started_, rate_from_, take_started_;
  long rate_ticks_ = 0, rate_frames_ = 0, rate_images_ = 0, take_images_ = 0, take_renders_ = 0;
  WindowFigures figures_;
  TissueSnapshot shown_;
  QLabel* guide_ = nullptr;
  QPushButton *next_button_ = nullptr, *answer_button_ = nullptr, *review_button_ = nullptr;
  std::unique_ptr<ReviewWindow> review_;
  QComboBox *lie_box_ = nullptr, *presentation_box_ = nullptr, *back_box_ = nullptr;
  QWidget* answers_ = nullptr;
  int step_ = 0;
  std::array<double, exercise::kManeuvers - 1> next_times_{};
  std::array<bool, exercise::kManeuvers> step_pictured_{};
};

}  // namespace fetouch::app::trainer

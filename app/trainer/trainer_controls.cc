// The trainer window's controls, as its buttons, shortcuts, mouse and tests call them: pause,
// reset, record, colour field, image plane, open a scene, local model and hold, camera and the mouse
// cursor (trainer_window.h). The window's build-up, its tick and its exports are in trainer_window.cc.
#include <QApplication>
#include <QComboBox>
#include <QKeyEvent>
#include <QLabel>
#include <QMouseEvent>
#include <QVTKOpenGLStereoWidget.h>
#include <QWheelEvent>
#include <vtkCamera.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkRenderer.h>

#include "app/scene_devices.h"
#include "app/trainer/trainer_window.h"
#include "app/trainer/ultrasound_volume.h"
#include "config/scene_loader.h"
#include "haptics/local_model.h"

namespace fetouch::app::trainer {

void TrainerWindow::toggle_pause() {
  if (!session_) return;
  session_->set_paused(!session_->paused());
}

void TrainerWindow::reset() {
  start_take(recording_);
  if (window_options_.exercise.on) {  // the exercise from its first maneuver, the fetus hidden again
    step_ = 0;
    hide_the_answer(true);
    show_exercise_step();
  }
}

void TrainerWindow::toggle_recording() {
  if (window_options_.exercise.on) {
    message_->setText("the exercise records its take itself (OUT/exercise/take.h5)");
    return;
  }
  if (recording_) {
    start_take(std::nullopt);
    return;
  }
  std::error_code ignored;
  std::filesystem::create_directories(window_options_.out, ignored);
  start_take(window_options_.out / ("take-" + std::to_string(takes_) + ".h5"));
}

void TrainerWindow::toggle_colour_field() {
  field_ = field_ == ColourField::displacement ? ColourField::von_mises : ColourField::displacement;
  if (session_) session_->want_stress(field_ == ColourField::von_mises);
  if (view_) view_->update_tissue(shown_, field_);
}

void TrainerWindow::toggle_plane() {
  lateral_x_ = !lateral_x_;
  imaged_frame_ = -3;  // the image shown is of the other plane: ask for a new one
}

bool TrainerWindow::open_scene(const std::filesystem::path& file) {
  if (window_options_.exercise.on) {
    message_->setText("the exercise keeps its scene: quit and start another (fetouch trainer SCENE --exercise leopold --seed S)");
    return false;
  }
  // The scene is checked whole before anything of the running one is let go: a broken file leaves
  // the session as it was, its reason (file:line) on the message line.
  std::optional<config::Scene> loaded;
  std::string refused;
  try {
    loaded = config::load_scene(file.string()).scene;
  } catch (const config::SceneError& error) {
    for (const auto& d : error.diagnostics()) refused += d.format() + "; ";
  } catch (const std::exception& e) {
    refused = file.string() + ": " + e.what();
  }
  if (loaded && loaded->probes.empty())
    refused = file.string() + ": the scene has no probes to touch the tissue with";
  ReferenceVolume volume;
  double gain = 1;
  std::string description;
  if (refused.empty()) try {
      volume = scene_ultrasound(*loaded, gain, description);
    } catch (const std::exception& e) {
      refused = file.string() + ": " + e.what();
    }
  if (!refused.empty()) {
    while (!refused.empty() && (refused.back() == ' ' || refused.back() == ';')) refused.pop_back();
    message_->setStyleSheet("color: #c00000");
    message_->setText(QString::fromStdString("cannot open " + file.string() + ": " + refused));
    return false;
  }
  scene_ = *loaded;
  scene_path_ = file;
  volume_ = std::make_shared<const ReferenceVolume>(std::move(volume)), gain_ = gain, volume_description_ = description;
  ultrasound_->setToolTip(QString::fromStdString("Ultrasound: " + volume_description_));
  setWindowTitle(QString::fromStdString("Fetouch trainer: " + scene_.name));
  const haptics::HapticLoopSettings scene_loop = loop_settings(scene_);
  model_ = asked_model_ = scene_loop.local_model, hold_ = asked_hold_ = scene_loop.hold;
  show_mode();
  message_->setStyleSheet("");
  start_take(std::nullopt);
  return session_ != nullptr;
}

void TrainerWindow::ask_mode(haptics::LocalModelKind model, haptics::HoldKind hold) {
  if (!session_) return;
  mode_request_ = session_->ask_mode(model, hold);
  asked_model_ = model, asked_hold_ = hold;  // M and H before the answer build on this request
  message_->setStyleSheet("");
  message_->setText(QString("asked for %1 + %2: the stability analysis runs on the next frame")
                        .arg(haptics::to_string(model), haptics::to_string(hold)));
}

void TrainerWindow::take_mode_verdict() {
  if (mode_request_ == 0) return;
  const haptics::ModeVerdict verdict = session_->mode_verdict();
  if (verdict.request != mode_request_) return;  // not answered yet (or an older request's answer)
  mode_request_ = 0;
  if (verdict.accepted) model_ = verdict.local_model, hold_ = verdict.hold;
  asked_model_ = model_, asked_hold_ = hold_;
  message_->setStyleSheet(verdict.accepted ? "" : "color: #c00000");
  message_->setText(QString::fromStdString(verdict.text));
  show_mode();
}

void TrainerWindow::show_mode() {
  model_box_->setCurrentIndex(model_box_->findData(static_cast<int>(model_)));
  hold_box_->setCurrentIndex(hold_box_->findData(static_cast<int>(hold_)));
}

std::string TrainerWindow::message() const { return message_->text().toStdString(); }
std::string TrainerWindow::status() const { return status_->text().toStdString(); }

void TrainerWindow::reset_camera() {
  if (!view_) return;
  vtkCamera* camera = renderer_->GetActiveCamera();
  camera->SetPosition(0, -1, 0.6);  // from the front and above: the probes press from +z
  camera->SetFocalPoint(0, 0, 0);
  camera->SetViewUp(0, 0, 1);
  view_->reset_camera();
}

void TrainerWindow::move_cursor_along_view(double metres) {
  if (!session_ || !session_->cursor()) return;
  const double* p = renderer_->GetActiveCamera()->GetDirectionOfProjection();
  set_cursor(cursor_ + metres * Eigen::Vector3d(p[0], p[1], p[2]));
}

bool TrainerWindow::switch_hand() {
  if (!session_ || !session_->switch_cursor()) {
    message_->setText("the mouse drives one hand only here");
    return false;
  }
  const int p = session_->cursor_probe();
  cursor_ = cursor_targets_[p];
  view_->show_cursor(true, cursor_);
  message_->setText(QString::fromStdString("the mouse drives " + session_->probe_names()[p] + "; the other hand holds where it is"));
  return true;
}

void TrainerWindow::set_cursor(const Eigen::Vector3d& at) {
  if (!session_ || !session_->cursor()) return;
  cursor_ = at;
  cursor_targets_[session_->cursor_probe()] = at;
  session_->cursor()->set_target(cursor_);
  view_->show_cursor(true, cursor_);
}

void TrainerWindow::set_cursor_at_display(double x, double y) {
  if (!session_ || !session_->cursor()) return;
  // The point under the mouse at the cursor's depth: the cursor moves in the view plane.
  renderer_->SetWorldPoint(cursor_.x(), cursor_.y(), cursor_.z(), 1);
  renderer_->WorldToDisplay();
  const double depth = renderer_->GetDisplayPoint()[2];
  const double ratio = vtk_widget_->devicePixelRatioF();
  renderer_->SetDisplayPoint(x * ratio, (vtk_widget_->height() - y) * ratio, depth);
  renderer_->DisplayToWorld();
  const double* w = renderer_->GetWorldPoint();
  if (w[3] == 0) return;
  set_cursor(Eigen::Vector3d(w[0] / w[3], w[1] / w[3], w[2] / w[3]));
}

bool TrainerWindow::eventFilter(QObject* watched, QEvent* event) {
  if (watched == vtk_widget_ && session_ && session_->cursor()) {
    if (event->type() == QEvent::MouseMove) {
      auto* e = static_cast<QMouseEvent*>(event);
      if (e->modifiers() & Qt::ShiftModifier) {
        set_cursor_at_display(e->localPos().x(), e->localPos().y());
        return true;
      }
    } else if (event->type() == QEvent::Wheel) {
      auto* e = static_cast<QWheelEvent*>(event);
      if (e->modifiers() & Qt::ShiftModifier) {
        move_cursor_along_view(e->angleDelta().y() > 0 ? 1e-3 : -1e-3);
        return true;
      }
    } else if (event->type() == QEvent::KeyPress) {
      auto* e = static_cast<QKeyEvent*>(event);
      if (e->key() == Qt::Key_BracketRight || e->key() == Qt::Key_BracketLeft) {
        move_cursor_along_view(e->key() == Qt::Key_BracketRight ? 1e-3 : -1e-3);
        return true;
      }
    }
  }
  return QMainWindow::eventFilter(watched, event);
}

}  // namespace fetouch::app::trainer

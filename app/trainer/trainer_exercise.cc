// The trainer window's Leopold exercise (trainer_window.h, docs/trainer.md): the guide, the
// answers, and the assessment of the take.
#include <QComboBox>
#include <QGridLayout>
#include <QLabel>
#include <QPushButton>
#include <QToolBar>
#include <QVBoxLayout>

#include <cstdio>

#include "app/recording.h"
#include "app/scene_mesh.h"
#include "app/trainer/review_window.h"
#include "app/trainer/trainer_window.h"

namespace fetouch::app::trainer {

namespace {

// The phantom's shapes as the scene's mesh was made from them (metres there: millimetres / 1000).
imaging::PhantomGeometry scene_phantom(const config::Scene& scene) {
  return imaging::phantom_geometry(phantom_settings(scene.mesh.phantom));
}

QComboBox* choices(QWidget* parent, const std::vector<std::string>& names) {
  auto* box = new QComboBox(parent);
  box->addItem("(choose)", QString());
  for (const std::string& name : names) box->addItem(QString::fromStdString(name), QString::fromStdString(name));
  return box;
}

template <class T>
std::optional<T> chosen(const QComboBox* box) {
  T value{};
  const std::string name = box->currentData().toString().toStdString();
  if (name.empty() || !config::parse(name, value)) return std::nullopt;
  return value;
}

}  // namespace

QWidget* TrainerWindow::build_exercise_panel() {
  auto* panel = new QWidget(this);
  auto* column = new QVBoxLayout(panel);
  guide_ = new QLabel(panel);
  guide_->setWordWrap(true);
  guide_->setTextFormat(Qt::RichText);
  guide_->setAlignment(Qt::AlignTop | Qt::AlignLeft);
  guide_->setMinimumHeight(140);
  column->addWidget(guide_, 1);
  answers_ = new QWidget(panel);
  auto* grid = new QGridLayout(answers_);
  lie_box_ = choices(answers_, config::lie_names());
  presentation_box_ = choices(answers_, config::presentation_names());
  back_box_ = choices(answers_, config::back_names());
  grid->addWidget(new QLabel("lie", answers_), 0, 0), grid->addWidget(lie_box_, 0, 1);
  grid->addWidget(new QLabel("presentation", answers_), 1, 0), grid->addWidget(presentation_box_, 1, 1);
  grid->addWidget(new QLabel("the back faces the mother's", answers_), 2, 0), grid->addWidget(back_box_, 2, 1);
  answer_button_ = new QPushButton("Answer", answers_);
  grid->addWidget(answer_button_, 3, 1);
  connect(answer_button_, &QPushButton::clicked, this, [this] {
    answer({chosen<config::FetalLie>(lie_box_), chosen<config::FetalPresentation>(presentation_box_), chosen<config::FetalBack>(back_box_)});
  });
  column->addWidget(answers_);
  next_button_ = new QPushButton("Next maneuver (N)", panel);
  next_button_->setShortcut(QKeySequence(Qt::Key_N));
  connect(next_button_, &QPushButton::clicked, this, [this] { next_maneuver(); });
  column->addWidget(next_button_);
  review_button_ = new QPushButton("Review the take", panel);
  review_button_->setToolTip("the hands' paths and forces over the fetus, scrubbable in time (fetouch review)");
  review_button_->setVisible(false);
  connect(review_button_, &QPushButton::clicked, this, [this] { open_review(); });
  column->addWidget(review_button_);
  return panel;
}

double TrainerWindow::simulated_s() {
  return session_ ? session_->monitor().ticks.load() * session_->loop().period_s : 0;
}

void TrainerWindow::hide_the_answer(bool hidden) {
  for (std::size_t i = 0; view_ && i < view_->regions(); ++i)
    if (view_->region_name(i) != "wall") set_region_visible(view_->region_name(i), !hidden);
  regions_bar_->setEnabled(!hidden);
  ultrasound_->setVisible(!hidden);
}

void TrainerWindow::show_exercise_step() {
  answers_->setVisible(step_ == exercise::kManeuvers);
  next_button_->setVisible(step_ < exercise::kManeuvers);
  if (step_ < exercise::kManeuvers) {
    const exercise::ManeuverGuide& g = exercise::leopold_guides()[step_];
    guide_->setText(QString::fromStdString("<b>Maneuver " + std::to_string(step_ + 1) + " of 4: " + g.name + "</b><br><br><i>Hands:</i> " +
                                           g.hands + "<br><br><i>Feel for:</i> " + g.feel_for +
                                           "<br><br>The ultrasound and the fetus stay hidden until you answer. N: the next maneuver."));
    next_button_->setText(step_ + 1 < exercise::kManeuvers ? "Next maneuver (N)" : "To the answers (N)");
  } else if (step_ == exercise::kManeuvers) {
    guide_->setText("<b>Your answers</b><br><br>How does the fetus lie, what presents at the pelvis, and which way does its back face?");
  }
}

bool TrainerWindow::next_maneuver() {
  if (!window_options_.exercise.on || step_ >= exercise::kManeuvers) {
    message_->setText(step_ == exercise::kManeuvers ? "answer now: the four maneuvers are done" : "no exercise under way");
    return false;
  }
  // A scripted change happens at its own time (the window's timer only notices it later).
  const auto& scripted = window_options_.exercise.maneuver_times;
  if (step_ + 1 < exercise::kManeuvers) next_times_[step_] = scripted ? (*scripted)[step_] : simulated_s();
  ++step_;
  show_exercise_step();
  return true;
}

void TrainerWindow::exercise_tick() {
  const ExerciseOptions& o = window_options_.exercise;
  if (!o.on) return;
  if (o.step_screenshots && step_ < exercise::kManeuvers && !step_pictured_[step_]) {
    const double begun = step_ == 0 ? 0 : next_times_[step_ - 1];
    if (simulated_s() >= begun + 1.7) {
      step_pictured_[step_] = true;
      picture_step("step-" + std::to_string(step_ + 1) + ".png");
    }
  }
  if (!o.maneuver_times || step_ + 1 >= exercise::kManeuvers) return;
  if (simulated_s() >= (*o.maneuver_times)[step_]) next_maneuver();
}

void TrainerWindow::picture_step(const std::string& name) {
  const std::filesystem::path file = *window_options_.exercise.step_screenshots / name;
  if (!save_screenshot(file)) message_->setText(QString::fromStdString("could not write " + file.string()));
}

void TrainerWindow::choose_answers(const exercise::Answers& given) {
  const auto choose = [](QComboBox* box, const std::optional<std::string>& name) {
    box->setCurrentIndex(name ? std::max(0, box->findData(QString::fromStdString(*name))) : 0);
  };
  choose(lie_box_, given.lie ? std::optional<std::string>(config::to_string(*given.lie)) : std::nullopt);
  choose(presentation_box_, given.presentation ? std::optional<std::string>(config::to_string(*given.presentation)) : std::nullopt);
  choose(back_box_, given.back ? std::optional<std::string>(config::to_string(*given.back)) : std::nullopt);
}

bool TrainerWindow::answer(const exercise::Answers& given) {
  if (!window_options_.exercise.on || step_ > exercise::kManeuvers || !session_ || !recording_) {
    message_->setText("no exercise to answer");
    return false;
  }
  if (step_ < exercise::kManeuvers && session_->running()) {
    message_->setText("answer after the fourth maneuver (N moves on)");
    return false;
  }
  // Maneuvers not begun when the take ended begin (and end) at its end; scripted ones at their times.
  const double end = simulated_s();
  const auto& scripted = window_options_.exercise.maneuver_times;
  for (int k = std::min(step_, exercise::kManeuvers - 1); k < exercise::kManeuvers - 1; ++k)
    next_times_[k] = scripted ? (*scripted)[k] : end;
  session_->request_stop();
  session_->wait();
  try {
    const Recording take = read_recording(*recording_);
    std::vector<exercise::HandTrack> hands;
    for (std::size_t d = 0; d < take.devices.size(); ++d) {
      exercise::HandTrack h;
      h.name = d < take.header.probes.size() ? take.header.probes[d] : "probe " + std::to_string(d);
      for (const DeviceSample& s : take.devices[d].samples) {
        h.time_s.push_back(s.time_s), h.position_m.push_back(s.position), h.force_n.push_back(s.force.norm());
        h.in_contact.push_back(s.in_contact);
      }
      hands.push_back(std::move(h));
    }
    const imaging::PhantomGeometry geometry = scene_phantom(scene_);
    exercise::AssessmentSettings settings;
    settings.comfort_limit_n = window_options_.exercise.comfort_limit_n;
    settings.comfort_limit_source = window_options_.exercise.comfort_limit_source;
    const config::FetalPose pose = scene_.mesh.phantom.pose.value_or(config::FetalPose{});
    figures_.assessment = exercise::assess(geometry, pose, hands, next_times_, given, settings);
    figures_.assessment_dir = window_options_.out / "exercise";
    exercise::write_assessment(*figures_.assessment, geometry, figures_.assessment_dir);
  } catch (const std::exception& e) {
    figures_.error = std::string("the exercise could not be assessed: ") + e.what();
    message_->setText(QString::fromStdString("error: " + figures_.error));
    return false;
  }
  step_ = exercise::kManeuvers + 1;
  hide_the_answer(false);
  // The fetus shown in its regions' own colours (C: back to the fields).
  field_ = ColourField::regions;
  if (view_) view_->update_tissue(shown_, field_);
  image_now();  // the ultrasound at once (the take has ended: no new frame would ask for it)
  answers_->setVisible(false);
  next_button_->setVisible(false);
  review_button_->setVisible(true);
  const exercise::Assessment& a = *figures_.assessment;
  std::string text = "<b>The fetus: " + config::describe(a.pose) + "</b><br><br>";
  for (const exercise::AnswerResult& r : a.answers)
    text += r.asked + ": " + (r.given.empty() ? "(none)" : r.given) + (r.score == 1 ? " (right)" : r.score > 0 ? " (nearly)" : " (wrong)") + "<br>";
  char line[200];
  std::snprintf(line, sizeof line, "<br>Maneuvers that reached what they are for: %d of 4. Abdomen covered: %.0f %%. Largest force %.2f N.",
                a.maneuvers_reached(), 100 * a.covered_share, a.largest_force_n);
  guide_->setText(QString::fromStdString(text + line));
  message_->setText(QString::fromStdString("wrote " + (figures_.assessment_dir / "report.md").string()));
  return true;
}

ReviewWindow* TrainerWindow::open_review() {
  if (!figures_.assessment) {
    message_->setText("the take is reviewed once it is assessed (answer first)");
    return nullptr;
  }
  try {
    review_ = std::make_unique<ReviewWindow>(load_review_take(figures_.assessment_dir), ReviewOptions{});
  } catch (const std::exception& e) {
    message_->setText(QString::fromStdString(std::string("the take cannot be reviewed: ") + e.what()));
    return nullptr;
  }
  review_->show();
  return review_.get();
}

}  // namespace fetouch::app::trainer

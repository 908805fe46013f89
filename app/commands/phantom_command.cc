// `fetouch phantom`: the synthetic fetal ultrasound phantom and its ground-truth labels as MetaImage
// volumes (imaging/phantom.h), with a JSON summary of what was generated.
#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "app/output_guard.h"
#include "app/json_writer.h"
#include "app/scene_mesh.h"
#include "config/fetal_pose.h"
#include "imaging/fetal_biometry.h"
#include "imaging/phantom.h"
#include "imaging/volume_io.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;

struct PhantomOptions {
  std::string out = "fetouch-phantom";
  unsigned int seed = 1;
  double spacing_mm = 1.0;
  std::vector<double> fetus_offset_mm{0, 0, 0};
  std::string lie, presentation, back, head_side;  // the fetal pose (config/fetal_pose.h); empty: not given
  double weeks = 0;                                // gestational age; 0: not given (the seed's 16-week fetus)
  bool no_speckle = false;
  bool json = false;
};

const char* label_name(int label) {
  switch (label) {
    case imaging::kTissue: return "tissue";
    case imaging::kUterineWall: return "uterine_wall";
    case imaging::kAmnioticFluid: return "amniotic_fluid";
    case imaging::kHead: return "head";
    case imaging::kSkull: return "skull";
    case imaging::kTrunk: return "trunk";
    case imaging::kLimb: return "limb";
  }
  return "unknown";
}

int run_phantom(const PhantomOptions& o) {
  imaging::PhantomSettings settings;
  settings.seed = o.seed;
  settings.spacing_mm = o.spacing_mm;
  for (int d = 0; d < 3; ++d) settings.fetus_offset_mm[d] = o.fetus_offset_mm[d];
  settings.speckle = !o.no_speckle;
  const auto start = std::chrono::steady_clock::now();
  imaging::Phantom phantom;
  std::optional<config::FetalPose> pose;
  try {
    pose = config::requested_pose(o.lie, o.presentation, o.back, o.head_side, o.seed);
    settings.fetus_orientation = phantom_orientation(pose);
    if (o.weeks > 0) settings.gestational_age_weeks = o.weeks;
    refuse_overwriting({}, {}, o.out);  // --out must be a folder (or not exist yet)
    phantom = imaging::make_phantom(settings);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  }
  const fs::path dir(o.out), image = dir / "phantom.mha", labels = dir / "phantom_labels.mha",
      summary = dir / "summary.json";
  try {
    fs::create_directories(dir);
    replace_when_written(image, [&](const fs::path& to) { imaging::write_volume(phantom.image, to); });
    replace_when_written(labels, [&](const fs::path& to) { imaging::write_volume(phantom.labels, to); });
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitFailure;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::map<int, double> volume_ml;
  for (const auto label : phantom.labels.data) volume_ml[label] += phantom.labels.voxel_volume_mm3() / 1000;
  std::ostringstream text;
  JsonWriter json(text);
  json.begin_object();
  json.key("seed").value(static_cast<long>(o.seed));
  json.key("spacing_mm").value(o.spacing_mm);
  json.key("fetus_offset_mm").begin_array();
  for (double v : o.fetus_offset_mm) json.value(v);
  json.end_array();
  if (pose) {
    json.key("pose").begin_object();
    json.key("lie").value(config::to_string(pose->lie));
    json.key("presentation").value(config::to_string(pose->presentation));
    json.key("back").value(config::to_string(pose->back));
    if (pose->lie != config::FetalLie::longitudinal) json.key("head_side").value(config::to_string(pose->head_side));
    json.key("head_direction").values(settings.fetus_orientation->head);
    json.key("back_direction").values(settings.fetus_orientation->back);
    json.end_object();
  }
  if (settings.gestational_age_weeks) {
    const double weeks = *settings.gestational_age_weeks;
    json.key("gestational_age").begin_object();
    json.key("weeks").value(weeks);
    json.key("hadlock_biparietal_diameter_mm").value(imaging::biparietal_diameter_mm(weeks));
    json.key("hadlock_abdominal_circumference_mm").value(imaging::abdominal_circumference_mm(weeks));
    json.key("hadlock_femur_length_mm").value(imaging::femur_length_mm(weeks));
    json.end_object();
  }
  json.key("dimensions").begin_array();
  for (int d : phantom.image.dimensions) json.value(static_cast<long>(d));
  json.end_array();
  json.key("origin_mm").values(phantom.image.origin_mm);
  json.key("speckle").value(settings.speckle);
  json.key("label_volumes_ml").begin_object();
  for (const auto& [label, ml] : volume_ml) json.key(label_name(label)).value(ml);
  json.end_object();
  json.key("labels").begin_object();
  for (int label = imaging::kTissue; label <= imaging::kLimb; ++label) json.key(label_name(label)).value(static_cast<long>(label));
  json.end_object();
  json.key("image").value(image.string());
  json.key("label_map").value(labels.string());
  json.key("seconds").value(seconds);
  json.end_object();
  text << "\n";
  try {
    write_text_file(summary, text.str());
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitFailure;
  }
  if (o.json) {
    std::cout << text.str();
  } else {
    std::cout << "phantom (seed " << o.seed << ", " << o.spacing_mm << " mm, " << phantom.image.dimensions[0] << " x "
              << phantom.image.dimensions[1] << " x " << phantom.image.dimensions[2] << " voxels) in " << seconds << " s\n"
              << (pose ? "  the fetus: " + config::describe(*pose) + "\n" : std::string())
              << "  wrote " << image.string() << " and " << labels.string() << " (open in ParaView or 3D Slicer), "
              << summary.string() << "\n";
  }
  return kExitOk;
}

}  // namespace

void add_phantom_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<PhantomOptions>();
  CLI::App* cmd = parent.add_subcommand("phantom", "Generate the synthetic fetal ultrasound phantom and its labels");
  cmd->footer(
      "A fetus-like body (head with skull, trunk, limbs) in amniotic fluid inside a uterine wall, with\n"
      "speckle, depth attenuation and shadowing, from a seed (the same seed gives the same bytes).\n"
      "Writes DIR/phantom.mha (0..255), DIR/phantom_labels.mha (0 tissue, 1 uterine wall, 2 amniotic\n"
      "fluid, 3 head, 4 skull, 5 trunk, 6 limb) and DIR/summary.json. Millimetres.\n"
      "The fetus lies as the seed puts it, or as --lie, --presentation, --back and --head-side say\n"
      "(the uterus frame: x towards the fundus, y the mother's right, z anterior).\n"
      "Example: fetouch phantom --seed 7 --spacing 0.8 --out phantom7\n"
      "         fetouch phantom --lie transverse --back superior --head-side right --out transverse");
  cmd->add_option("--out", o->out, "Output folder")->capture_default_str();
  cmd->add_option("--seed", o->seed, "Random seed")->capture_default_str();
  cmd->add_option("--spacing", o->spacing_mm, "Voxel size in mm")->check(CLI::Range(0.2, 10.0))->capture_default_str();
  cmd->add_option("--fetus-offset", o->fetus_offset_mm,
                  "Move the fetus by X Y Z mm from where the seed puts it (each within 50 mm; the wall cuts it off where it reaches it)")
      ->expected(3)
      ->check(CLI::Range(-50.0, 50.0));
  cmd->add_option("--lie", o->lie, "The fetus's lie (docs/meshing.md); random: the whole pose drawn from the seed")
      ->check(CLI::IsMember(config::requested_lie_names()));
  cmd->add_option("--presentation", o->presentation, "What lies over the pelvis (with --lie)")
      ->check(CLI::IsMember(config::presentation_names()));
  cmd->add_option("--back", o->back, "Where the fetal back faces (with --lie)")->check(CLI::IsMember(config::back_names()));
  cmd->add_option("--head-side", o->head_side, "The mother's side the head lies on (transverse and oblique lies)")
      ->check(CLI::IsMember(config::side_names()));
  cmd->add_option("--gestational-age", o->weeks,
                  "Grow the fetus (and the uterus) to this age in weeks by Hadlock's biometry (without: about 16 weeks)")
      ->check(CLI::Range(14.0, 42.0));
  cmd->add_flag("--no-speckle", o->no_speckle, "Echogenicity, attenuation and shadows only");
  cmd->add_flag("--json", o->json, "Print the JSON summary on stdout");
  cmd->callback([o, &exit_code]() { exit_code = run_phantom(*o); });
}

}  // namespace fetouch::app

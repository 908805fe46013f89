// `fetouch reconstruct`: a 3D volume from a tracked freehand sweep and its calibration
// (imaging/reconstruction.h), written as compressed MetaImage, with a JSON summary.
#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "app/json_writer.h"
#include "app/output_guard.h"
#include "imaging/reconstruction.h"
#include "imaging/volume_io.h"

namespace fetouch::app {

namespace {

struct ReconstructOptions {
  std::string sweep, calibration, out = "reconstructed.mha";
  double spacing_mm = 0.5;
  bool nearest = false, maximum = false, no_fill = false, json = false;
};

int run_reconstruct(const ReconstructOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  imaging::ReconstructionSettings settings;
  settings.spacing_mm = o.spacing_mm;
  settings.linear = !o.nearest;
  settings.maximum = o.maximum;
  settings.fill_holes = !o.no_fill;
  imaging::Reconstruction result;
  try {
    refuse_overwriting({o.out}, {{o.sweep, "the sweep"}, {o.calibration, "the calibration"}});
    const imaging::TrackedSweep sweep = imaging::read_tracked_sweep(o.sweep);
    const imaging::Matrix4 calibration = imaging::read_image_to_probe(o.calibration);
    result = imaging::reconstruct(sweep, calibration, settings);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  }
  try {
    const std::filesystem::path out(o.out);
    if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
    replace_when_written(out, [&](const std::filesystem::path& to) { imaging::write_volume(result.volume, to); });
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitFailure;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto& v = result.volume;
  if (o.json) {
    std::ostringstream text;
    JsonWriter json(text);
    json.begin_object();
    json.key("volume").value(o.out);
    json.key("dimensions").begin_array();
    for (int d : v.dimensions) json.value(static_cast<long>(d));
    json.end_array();
    json.key("spacing_mm").value(o.spacing_mm);
    json.key("origin_mm").values(v.origin_mm);
    json.key("frames_used").value(static_cast<long>(result.frames_used));
    json.key("frames_skipped").value(static_cast<long>(result.frames_skipped));
    json.key("filled_fraction").value(result.filled_fraction);
    json.key("seconds").value(seconds);
    json.end_object();
    std::cout << text.str() << "\n";
  } else {
    std::cout << "reconstructed " << v.dimensions[0] << " x " << v.dimensions[1] << " x " << v.dimensions[2] << " voxels of "
              << o.spacing_mm << " mm from " << result.frames_used << " frames (" << result.frames_skipped
              << " without a valid pose), " << 100 * result.filled_fraction << " % filled, in " << seconds << " s\n"
              << "  wrote " << o.out << " (open in ParaView or 3D Slicer)\n";
  }
  return kExitOk;
}

}  // namespace

void add_reconstruct_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<ReconstructOptions>();
  CLI::App* cmd = parent.add_subcommand("reconstruct", "Reconstruct a 3D volume from a tracked freehand sweep");
  cmd->footer(
      "Reads a PLUS sequence file (.igs.mha: frames with Seq_FrameNNNN_ProbeToTrackerTransform and\n"
      "_ReferenceToTrackerTransform) and the Image-to-Probe calibration of a PLUS configuration file,\n"
      "pastes every pixel into a volume in the reference frame (linear or nearest, mean or maximum\n"
      "compounding), fills small holes, and writes compressed MetaImage (mm).\n"
      "Example: fetouch reconstruct ../shared/data/ultrasound/spine_phantom_freehand_sweep.igs.mha\n"
      "           --calibration ../shared/data/ultrasound/spine_phantom_freehand_calibration.xml --out spine.mha");
  cmd->add_option("sweep", o->sweep, "Tracked sweep (.igs.mha)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--calibration", o->calibration, "PLUS configuration with the Image-to-Probe transform")
      ->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "Output volume (.mha, .mhd or .vti)")->capture_default_str();
  cmd->add_option("--spacing", o->spacing_mm, "Voxel size in mm")->check(CLI::Range(0.05, 10.0))->capture_default_str();
  cmd->add_flag("--nearest", o->nearest, "Nearest-voxel pasting instead of trilinear splatting");
  cmd->add_flag("--maximum", o->maximum, "Maximum compounding instead of the weighted mean");
  cmd->add_flag("--no-fill", o->no_fill, "Leave holes between frames empty");
  cmd->add_flag("--json", o->json, "Print a JSON summary on stdout");
  cmd->callback([o, &exit_code]() { exit_code = run_reconstruct(*o); });
}

}  // namespace fetouch::app

// write_assessment: DIR/assessment.json, DIR/coverage.png and DIR/report.md (app/exercise/leopold.h).
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "app/exercise/leopold.h"
#include "app/json_writer.h"

namespace fetouch::app::exercise {

namespace {

namespace fs = std::filesystem;

using Rgb = std::array<unsigned char, 3>;

// The coverage map as a picture of the frontal plane to scale, seen as the trainee sees the mother
// lying before them: the fundus at the top, the mother's right on the picture's left. Untouched abdomen light grey; pressed cells
// green, darker the harder (up to the comfort limit, or 3 N), red above the limit; each maneuver's
// targets outlined in its own colour.
void write_png(const Assessment& a, const imaging::PhantomGeometry& geometry, const fs::path& png) {
  const AbdomenMap map(geometry);
  // 320 pixels along the mother's axis, the width in proportion: the frontal plane to scale.
  const int n = a.settings.coverage_cells, size = 320;
  const int width = std::max(1, static_cast<int>(std::lround(size * map.radii_mm().y() / map.radii_mm().x())));
  const double full = a.settings.comfort_limit_n > 0 ? a.settings.comfort_limit_n : 3.0;
  vtkNew<vtkImageData> image;
  image->SetDimensions(width, size, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* pixels = static_cast<unsigned char*>(image->GetScalarPointer());
  // Pixel (x, y), y up (VTK's rows start at the bottom): s from -1 (bottom) to 1, t from 1 (left) to -1.
  const auto st_of = [size, width](int x, int y) {
    return Eigen::Vector2d(-1 + (y + 0.5) * 2.0 / size, 1 - (x + 0.5) * 2.0 / width);
  };
  const std::array<Rgb, kManeuvers> outline{Rgb{200, 40, 40}, Rgb{40, 80, 220}, Rgb{150, 60, 170}, Rgb{230, 140, 20}};
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < width; ++x) {
      const Eigen::Vector2d st = st_of(x, y);
      Rgb c{255, 255, 255};
      if (st.norm() <= 1) {
        const int i = std::min(n - 1, int((st.x() + 1) * n / 2)), j = std::min(n - 1, int((st.y() + 1) * n / 2));
        const double f = a.coverage[std::size_t(i) * n + j];
        if (f <= 0) c = {225, 225, 225};
        else if (a.settings.comfort_limit_n > 0 && f > a.settings.comfort_limit_n) c = {220, 30, 30};
        else {
          const double u = std::clamp(f / full, 0.0, 1.0);
          c = {static_cast<unsigned char>(200 - 170 * u), static_cast<unsigned char>(235 - 105 * u), static_cast<unsigned char>(200 - 170 * u)};
        }
      }
      const Eigen::Vector2d p = map.unmap_mm(st);
      for (int k = 0; k < kManeuvers; ++k)
        for (const Target& t : a.maneuvers[k].targets)
          if (std::abs((p - t.centre_mm).norm() - t.radius_mm) < 1.0) c = outline[k];
      std::copy(c.begin(), c.end(), pixels + 3 * (std::size_t(y) * width + x));
    }
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(png.string().c_str());
  writer->SetInputData(image);
  writer->Write();
  if (writer->GetErrorCode() != 0 || !fs::exists(png)) throw std::runtime_error(png.string() + ": cannot be written");
}

void write_json(const Assessment& a, const fs::path& file) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot be written");
  JsonWriter json(out);
  json.begin_object();
  json.key("pose").begin_object();
  json.key("lie").value(config::to_string(a.pose.lie));
  json.key("presentation").value(config::to_string(a.pose.presentation));
  json.key("back").value(config::to_string(a.pose.back));
  json.key("head_side").value(config::to_string(a.pose.head_side));
  json.key("description").value(config::describe(a.pose));
  json.end_object();
  json.key("answers").begin_array();
  for (const AnswerResult& r : a.answers) {
    json.begin_object();
    json.key("asked").value(r.asked).key("given").value(r.given).key("truth").value(r.truth).key("score").value(r.score);
    json.end_object();
  }
  json.end_array();
  json.key("maneuvers").begin_array();
  for (const ManeuverResult& m : a.maneuvers) {
    json.begin_object();
    json.key("name").value(leopold_guides()[static_cast<int>(m.maneuver)].name);
    json.key("start_s").value(m.start_s).key("end_s").value(m.end_s);
    json.key("zones_touched").begin_array();
    for (const bool z : m.zones_touched) json.value(z);
    json.end_array();
    json.key("targets").begin_array();
    for (std::size_t t = 0; t < m.targets.size(); ++t) {
      json.begin_object();
      json.key("what").value(m.targets[t].what);
      json.key("centre_m").begin_array().value(1e-3 * m.targets[t].centre_mm.x()).value(1e-3 * m.targets[t].centre_mm.y()).end_array();
      json.key("radius_m").value(1e-3 * m.targets[t].radius_mm);
      json.key("reached").value(static_cast<bool>(m.targets_reached[t]));
      json.end_object();
    }
    json.end_array();
    json.key("largest_force_n").value(m.largest_force_n);
    json.key("reached").value(m.reached());
    json.end_object();
  }
  json.end_array();
  json.key("duration_s").value(a.duration_s);
  json.key("largest_force_n").value(a.largest_force_n);
  json.key("comfort_limit_n").value(a.settings.comfort_limit_n);
  json.key("comfort_limit_source").value(a.settings.comfort_limit_source);
  json.key("time_over_limit_s").value(a.time_over_limit_s);
  json.key("palpation_force_n").value(a.settings.palpation_force_n);
  json.key("covered_share").value(a.covered_share);
  json.key("coverage_cells").value(a.settings.coverage_cells);
  json.key("coverage_n").values(a.coverage);
  json.end_object();
  out << "\n";
  if (!out) throw std::runtime_error(file.string() + ": cannot be written");
}

void write_markdown(const Assessment& a, const fs::path& file) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot be written");
  char line[400];
  out << "# Leopold maneuvers: assessment\n\n";
  out << "The fetus: " << config::describe(a.pose) << ".\n\n";
  out << "| question | answer | the fetus | score |\n|---|---|---|---|\n";
  for (const AnswerResult& r : a.answers)
    out << "| " << r.asked << " | " << (r.given.empty() ? "(none)" : r.given) << " | " << r.truth << " | " << r.score << " |\n";
  out << "\n| maneuver | from | to | largest force | reached |\n|---|---|---|---|---|\n";
  for (const ManeuverResult& m : a.maneuvers) {
    std::string missed;
    for (std::size_t z = 0; z < m.zones_touched.size(); ++z)
      if (!m.zones_touched[z]) missed += (missed.empty() ? "" : "; ") + std::string(m.zones_touched.size() > 1 ? (z == 0 ? "the left hand's zone" : "the right hand's zone") : "its zone") + " not pressed";
    for (std::size_t t = 0; t < m.targets.size(); ++t)
      if (!m.targets_reached[t]) missed += (missed.empty() ? "" : "; ") + m.targets[t].what + " not reached";
    std::snprintf(line, sizeof line, "| %s | %.1f s | %.1f s | %.2f N | %s |\n", leopold_guides()[static_cast<int>(m.maneuver)].name.c_str(),
                  m.start_s, m.end_s, m.largest_force_n, m.reached() ? "yes" : ("no: " + missed).c_str());
    out << line;
  }
  std::snprintf(line, sizeof line, "\nTime: %.1f s. Largest force: %.2f N", a.duration_s, a.largest_force_n);
  out << line;
  if (a.settings.comfort_limit_n > 0) {
    std::snprintf(line, sizeof line, " against a comfort limit of %.2f N (%s); %.2f s above it", a.settings.comfort_limit_n,
                  a.settings.comfort_limit_source.c_str(), a.time_over_limit_s);
    out << line;
  }
  std::snprintf(line, sizeof line, ". Abdomen covered (pressed with at least %.2f N): %.0f %%.\n\n", a.settings.palpation_force_n,
                100 * a.covered_share);
  out << line;
  out << "![The abdomen seen from the front, the fundus at the top and the mother's right on the left: pressed cells green "
         "(darker the harder, red above the limit), each maneuver's targets outlined](coverage.png)\n\n"
         "The outlines: red what the fundal grip is for, blue the umbilical grip's (the back and the small parts), "
         "purple Pawlik's grip's, orange the pelvic grip's (either side of the presenting part).\n";
  if (!out) throw std::runtime_error(file.string() + ": cannot be written");
}

}  // namespace

void write_assessment(const Assessment& assessment, const imaging::PhantomGeometry& geometry, const fs::path& dir) {
  std::error_code error;
  fs::create_directories(dir, error);
  if (error) throw std::runtime_error(dir.string() + ": cannot be created: " + error.message());
  write_json(assessment, dir / "assessment.json");
  write_png(assessment, geometry, dir / "coverage.png");
  write_markdown(assessment, dir / "report.md");
}

}  // namespace fetouch::app::exercise

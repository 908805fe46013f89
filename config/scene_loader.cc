#include "config/scene_loader.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <tuple>
#include <set>
#include <sstream>

#include "config/plausible.h"
#include "config/section_readers.h"
#include "config/yaml_reader.h"

namespace fetouch::config {

namespace detail {

std::string format_number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// Reports each key of `keys` present in `map` as not used in the situation `why` describes.
void reject_keys(MapView& map, const std::vector<std::string>& keys, const std::string& why) {
  for (const auto& key : keys) {
    if (!map.has(key)) continue;
    const Entry e = map.entry(key);
    map.reader().error(e.key_mark, e.path, "'" + key + "' is not used " + why);
  }
}

}  // namespace detail

using detail::Choices;
using detail::Entry;
using detail::MapView;
using detail::Need;
using detail::Range;
using detail::Reader;
using namespace detail;

namespace {

const Choices<ElementType> kElements{
    {"p1", ElementType::p1}, {"p2", ElementType::p2}, {"q1", ElementType::q1}, {"q2", ElementType::q2}};
const Choices<GeneratedShape> kShapes{{"box", GeneratedShape::box},
                                      {"ball", GeneratedShape::ball},
                                      {"shell", GeneratedShape::shell}};
const Choices<MeshSurface> kSurfaces{{"restricted", MeshSurface::restricted},
                                     {"contoured", MeshSurface::contoured},
                                     {"conforming", MeshSurface::conforming}};
const Choices<SmoothingFilter> kFilters{{"none", SmoothingFilter::none},
                                        {"gaussian", SmoothingFilter::gaussian},
                                        {"median", SmoothingFilter::median}};



// ---- mesh ---------------------------------------------------------------------------------------

// mesh.phantom's pose keys (config/fetal_pose.h, requested_pose): none, the seed's fetus as it
// always was; `lie` alone, that lie's usual presentation and back; `lie: random`, a pose drawn from
// the seed.
void read_fetal_pose(MapView& phantom, PhantomSource& out) {
  const std::vector<std::string> keys{"lie", "presentation", "back", "head_side"};
  const std::vector<const std::vector<std::string>*> names{&requested_lie_names(), &presentation_names(), &back_names(),
                                                         &side_names()};
  std::array<std::string, 4> given;
  bool known = true;
  for (std::size_t k = 0; k < keys.size(); ++k) {
    if (!phantom.has(keys[k])) continue;
    Choices<std::string> choices;
    for (const auto& name : *names[k]) choices.emplace_back(name, name);
    known = phantom.choice(keys[k], given[k], choices) && known;
  }
  if (!known) return;
  try {
    out.pose = requested_pose(given[0], given[1], given[2], given[3], static_cast<std::uint32_t>(out.seed));
  } catch (const PoseError& e) {
    const Entry where = phantom.entry(phantom.has(e.key()) ? e.key() : "lie");
    phantom.reader().error(where.value_mark, where.path, e.what());
  }
}

void read_generated(MapView& parent, GeneratedMesh& out) {
  const Entry e = parent.entry("generate");
  MapView map(parent.reader(), e.value, e.path, e.key_mark,
              {"shape", "size_m", "radius_m", "inner_radius_m", "refinements"});
  if (!map.valid()) return;
  if (!map.choice("shape", out.shape, kShapes, Need::required)) return;
  map.integer("refinements", out.refinements, {0, 6}, Need::optional);
  switch (out.shape) {
    case GeneratedShape::box: {
      reject_keys(map, {"radius_m", "inner_radius_m"}, "by shape box (it takes size_m)");
      if (map.vec3("size_m", out.size_m, Need::required)) {
        for (double s : out.size_m)
          if (!plausible::tissue_length_m.contains(s)) {
            const Entry size = map.entry("size_m");
            map.reader().error(size.value_mark, size.path,
                               "an edge of " + format_number(s) + " m; every edge length must be " +
                                   plausible::tissue_length_m.describe());
            break;
          }
      }
      break;
    }
    case GeneratedShape::ball:
      reject_keys(map, {"size_m", "inner_radius_m"}, "by shape ball (it takes radius_m)");
      map.number("radius_m", out.radius_m, plausible::tissue_length_m, Need::required);
      break;
    case GeneratedShape::shell:
      reject_keys(map, {"size_m"}, "by shape shell (it takes radius_m and inner_radius_m)");
      if (map.number("radius_m", out.radius_m, plausible::tissue_length_m, Need::required) &&
          map.number("inner_radius_m", out.inner_radius_m, plausible::tissue_length_m, Need::required) &&
          out.inner_radius_m >= out.radius_m) {
        const Entry inner = map.entry("inner_radius_m");
        map.reader().error(inner.value_mark, inner.path,
                           "must be smaller than radius_m (" + format_number(out.radius_m) +
                               "), got " + format_number(out.inner_radius_m));
      }
      break;
  }
}

void read_meshing(MapView& parent, MeshingOptions& out) {
  const Entry e = parent.entry("meshing");
  MapView map(parent.reader(), e.value, e.path, e.key_mark,
              {"target_size_m", "labels", "regions", "fetus", "threshold", "smoothing", "smoothing_sigma_m",
               "closing_voxels", "refine", "surface", "sizes", "image_regions"});
  if (!map.valid()) return;
  map.number("target_size_m", out.target_size_m, plausible::element_size_m);
  if (map.has("threshold")) {
    double threshold = 0;
    if (map.number("threshold", threshold, Range::any())) out.threshold = threshold;
  }
  // A list of labels such as [3, 4, 5, 6] (whole numbers in low..high).
  const auto label_list = [&](const Entry& labels, int high, std::vector<int>& into) {
    if (!labels.value.IsSequence() || labels.value.size() == 0) {
      map.reader().error(labels.value_mark, labels.path,
                         "expected a list of labels such as [3, 4, 5, 6], found " + detail::describe_node(labels.value));
      return;
    }
    for (std::size_t i = 0; i < labels.value.size(); ++i) {
      Entry item = labels;
      item.value.reset(labels.value[i]);
      item.value_mark = labels.value[i].Mark();
      item.path = labels.path + "[" + std::to_string(i) + "]";
      const auto x = detail::read_number(map.reader(), item);
      if (!x) continue;
      if (*x != std::floor(*x) || *x < 0 || *x > high)
        map.reader().error(item.value_mark, item.path,
                           "a label is a whole number from 0 to " + std::to_string(high) + ", not " + format_number(*x));
      else
        into.push_back(static_cast<int>(*x));
    }
  };
  if (map.has("labels")) label_list(map.entry("labels"), 65535, out.labels);
  if (map.has("regions")) {  // name: [labels]; their union is the tissue
    const Entry regions = map.entry("regions");
    std::vector<std::string> names;
    if (regions.value.IsMap())
      for (auto it = regions.value.begin(); it != regions.value.end(); ++it)
        if (it->first.IsScalar()) names.push_back(it->first.Scalar());
    if (names.empty()) {
      map.reader().error(regions.value_mark, regions.path,
                         "expected region names with their labels, such as {wall: [1], fluid: [2], fetus: [3, 4, 5, 6]}");
    } else if (map.has("labels")) {
      map.reader().error(regions.key_mark, regions.path, "give labels or regions, not both (the regions' labels are the tissue)");
    } else {
      MapView named(map.reader(), regions.value, regions.path, regions.key_mark, names);
      for (const std::string& name : names) {
        if (!named.has(name) || std::any_of(out.regions.begin(), out.regions.end(), [&](const auto& r) { return r.first == name; }))
          continue;
        std::vector<int> labels;
        label_list(named.entry(name), 255, labels);
        out.regions.emplace_back(name, labels);
        out.labels.insert(out.labels.end(), labels.begin(), labels.end());
      }
    }
  }
  if (map.has("image_regions")) {  // {segmented: NAME, imaged: NAME}: the label map made from the image
    const Entry pair = map.entry("image_regions");
    MapView names(map.reader(), pair.value, pair.path, pair.key_mark, {"segmented", "imaged"});
    std::string segmented, imaged;
    if (names.valid() && names.text("segmented", segmented, Need::required) && names.text("imaged", imaged, Need::required)) {
      if (!out.regions.empty() || !out.labels.empty())
        map.reader().error(pair.key_mark, pair.path, "image_regions makes the regions from an intensity image: drop regions and labels");
      else if (segmented == imaged)
        map.reader().error(pair.value_mark, pair.path, "the segmented and the imaged regions need two names, not '" + imaged + "' twice");
      else
        out.regions = {{imaged, {1}}, {segmented, {2}}}, out.regions_from_image = true;
    }
  }
  map.boolean("fetus", out.fetus);
  const int ways = !out.labels.empty() + out.fetus + out.threshold.has_value();
  if (ways > 1)
    map.reader().error(e.key_mark, e.path,
                       "give one of labels (a label map), fetus (a fetal volume) or threshold (an intensity volume)");
  map.choice("smoothing", out.smoothing, kFilters);
  map.number("smoothing_sigma_m", out.smoothing_sigma_m, plausible::smoothing_sigma_m);
  map.integer("closing_voxels", out.closing_voxels, {0, 10});
  map.choice("surface", out.surface, kSurfaces);
  if (out.surface == MeshSurface::conforming && out.regions.empty() && map.has("surface"))
    map.reader().error(map.entry("surface").value_mark, map.child_path("surface"),
                       "`conforming` meshes a label map in regions: give meshing.regions (e.g. {wall: [1], fluid: [2]})");
  if (map.has("sizes")) {  // region: size (m)
    const Entry sizes = map.entry("sizes");
    std::vector<std::string> names;
    if (sizes.value.IsMap())
      for (auto it = sizes.value.begin(); it != sizes.value.end(); ++it)
        if (it->first.IsScalar()) names.push_back(it->first.Scalar());
    if (names.empty()) {
      map.reader().error(sizes.value_mark, sizes.path, "expected region names with element sizes, such as {body: 0.003, wall: 0.006}");
    } else if (out.surface != MeshSurface::conforming) {
      map.reader().error(sizes.key_mark, sizes.path, "per-region sizes need `surface: conforming` (the other meshers make one size)");
    } else {
      MapView named(map.reader(), sizes.value, sizes.path, sizes.key_mark, names);
      for (const std::string& name : names) {
        if (std::none_of(out.regions.begin(), out.regions.end(), [&](const auto& r) { return r.first == name; })) {
          named.reader().error(named.entry(name).key_mark, named.child_path(name),
                               "no region '" + name + "' in meshing.regions");
          continue;
        }
        double size = 0;
        if (named.number(name, size, plausible::element_size_m, Need::required)) out.sizes_m.emplace_back(name, size);
      }
    }
  }
  if (map.has("refine")) {
    const Entry r = map.entry("refine");
    MapView refine(map.reader(), r.value, r.path, r.key_mark, {"center_m", "radius_m", "size_m", "around_probes"});
    if (refine.valid()) refine.boolean("around_probes", out.refine_around_probes);
    Vec3 center{};
    double radius = 0;
    if (out.refine_around_probes) {  // the ball is the probes' (app/scene_mesh.h)
      for (const char* key : {"center_m", "radius_m"})
        if (refine.has(key)) {
          const Entry given = refine.entry(key);
          map.reader().error(given.key_mark, given.path,
                             "'" + std::string(key) + "' is not used with around_probes: true (the ball holds the probes' trajectories)");
        }
      refine.number("size_m", out.refine_size_m, plausible::element_size_m, Need::required);
    } else if (refine.valid() && refine.vec3("center_m", center, Need::required) &&
               refine.number("radius_m", radius, plausible::tissue_length_m, Need::required) &&
               refine.number("size_m", out.refine_size_m, plausible::element_size_m, Need::required)) {
      out.refine_balls = {{center, radius}};
    }
  }
}

void read_mesh(MapView& scene, MeshSpec& out) {
  const Entry e = scene.entry("mesh");
  out.where = {e.key_mark.line + 1, e.key_mark.column + 1};
  MapView map(scene.reader(), e.value, e.path, e.key_mark,
              {"file", "volume", "phantom", "generate", "meshing", "element"});
  if (!map.valid()) return;
  const int sources = int(map.has("file")) + int(map.has("volume")) + int(map.has("phantom")) + int(map.has("generate"));
  if (sources != 1) {
    map.reader().error(map.mark(), map.path(),
                       sources == 0 ? "give the mesh as one of file, volume, phantom or generate"
                                    : "give only one of file, volume, phantom or generate");
    return;
  }
  map.choice("element", out.element, kElements);
  if (map.has("file")) {
    out.source = MeshSource::file;
    map.existing_path("file", out.path, Need::required, {".msh", ".vtu"});
  } else if (map.has("volume")) {
    out.source = MeshSource::volume;
    map.existing_path("volume", out.path, Need::required, {".mha", ".mhd", ".vti", ".nrrd", ".nhdr"},
                      /*allow_directory=*/true);
  } else if (map.has("phantom")) {
    out.source = MeshSource::phantom;
    const Entry p = map.entry("phantom");
    MapView phantom(map.reader(), p.value, p.path, p.key_mark,
                    {"seed", "spacing_m", "fetus_offset_m", "lie", "presentation", "back", "head_side",
                     "gestational_age_weeks"});
    if (phantom.valid()) {
      phantom.integer("seed", out.phantom.seed, {0, 2147483647});
      phantom.number("spacing_m", out.phantom.spacing_m, {2.5e-4, 5e-3, false, false});
      phantom.vec3("fetus_offset_m", out.phantom.fetus_offset_m, Need::optional,
                   {-0.05, 0.05, false, false, "-0.05 to 0.05 m: the sac is about 0.1 m across"});
      read_fetal_pose(phantom, out.phantom);
      double weeks = 0;
      if (phantom.has("gestational_age_weeks") &&
          phantom.number("gestational_age_weeks", weeks, {14, 42, false, false, "14 to 42 weeks: Hadlock's biometry (docs/meshing.md)"}))
        out.phantom.gestational_age_weeks = weeks;
    }
  } else {
    out.source = MeshSource::generated;
    read_generated(map, out.generated);
  }
  if (map.has("meshing")) {
    if (out.source == MeshSource::volume || out.source == MeshSource::phantom) {
      read_meshing(map, out.meshing);
    } else {
      const Entry meshing = map.entry("meshing");
      map.reader().error(meshing.key_mark, meshing.path,
                         "meshing options apply only to a mesh made from a volume or the phantom (mesh.volume, mesh.phantom)");
    }
  }
  // The phantom's label map: the whole uterus (wall, fluid, fetus) unless the options choose.
  if (out.source == MeshSource::phantom && out.meshing.labels.empty() && !out.meshing.fetus && !out.meshing.threshold)
    out.meshing.labels = {1, 2, 3, 4, 5, 6};
}

}  // namespace

bool Effects::has(Effect effect) const {
  if (effect == Effect::elasticity) return true;
  return std::find(listed.begin(), listed.end(), effect) != listed.end();
}

int Haptics::ratio(const Solver& solver) const {
  return static_cast<int>(std::lround(rate_hz / solver.rate_hz));
}

namespace {

constexpr std::uintmax_t kMaxSceneBytes = 1u << 20;

// The 0-based line of a document start marker ("---") that follows content, if any.
std::optional<int> second_document_line(const std::string& text) {
  std::istringstream lines(text);
  bool content = false;
  int number = 0;
  for (std::string line; std::getline(lines, line); ++number) {
    const bool marker = line.rfind("---", 0) == 0 && (line.size() == 3 || std::isspace(static_cast<unsigned char>(line[3])));
    if (marker && content) return number;
    const auto first = line.find_first_not_of(" \t\r");
    if (!marker && first != std::string::npos && line[first] != '#' && line[0] != '%') content = true;
  }
  return std::nullopt;
}

}  // namespace

LoadedScene parse_scene(const std::string& text, const std::string& label,
                        const std::filesystem::path& base_dir) {
  Reader reader(label, base_dir);
  // YAML is UTF-8 text: a NUL byte or a byte that is not UTF-8 means a binary or damaged file.
  if (const auto bad = first_non_text_byte(text)) {
    const YAML::Mark mark = mark_at(text, *bad);
    char byte[8];
    std::snprintf(byte, sizeof byte, "0x%02X", static_cast<unsigned char>(text[*bad]));
    reader.error(mark, "", std::string(text[*bad] == '\0' ? "a NUL byte" : "byte " + std::string(byte) + ", not UTF-8") +
                               "; a scene is UTF-8 YAML text");
    throw SceneError(reader.diagnostics());
  }
  YAML::Node root;
  try {
    // One document: a '---' line after content starts a second, which YAML::Load would drop
    // silently. (Not YAML::LoadAll: on stray closing brackets it yields empty documents for minutes.)
    if (const auto second = second_document_line(text)) {
      YAML::Mark mark;
      mark.line = *second;
      reader.error(mark, "", "a second YAML document (after '---'); a scene file holds one");
      throw SceneError(reader.diagnostics());
    }
    root = YAML::Load(text);
  } catch (const YAML::ParserException& error) {
    reader.error(error.mark, "", "YAML syntax: " + error.msg);
    throw SceneError(reader.diagnostics());
  }
  if (root.IsNull()) {
    reader.error(YAML::Mark::null_mark(), "",
                 "the scene is empty; it needs at least a mesh and a material");
    throw SceneError(reader.diagnostics());
  }

  LoadedScene loaded;
  Scene& s = loaded.scene;
  s.text = text;
  MapView scene(reader, root, "", root.Mark(),
                {"name", "description", "units", "mesh", "material", "materials", "effects",
                 "boundary", "solver", "haptics", "probes"});
  if (scene.valid()) {
    scene.text("name", s.name);
    scene.text("description", s.description);
    std::string units = "SI";
    if (scene.text("units", units) && units != "SI")
      reader.error(scene.entry("units").value_mark, "units",
                   "only SI is supported (m, N, s, Pa, kg), got '" + units + "'");
    scene.require("mesh", "file, volume or generate");
    if (scene.has("mesh")) read_mesh(scene, s.mesh);
    read_materials(scene, s);
    if (scene.has("effects")) read_effects(scene, s.effects);
    if (scene.has("boundary")) read_boundary(scene, s.boundary);
    if (scene.has("solver")) read_solver(scene, s.solver);
    if (scene.has("haptics")) read_haptics(scene, s.haptics);
    if (scene.has("probes")) read_probes(scene, s.probes);
    check_cross_fields(scene, s);
  }

  std::vector<Diagnostic> errors;
  for (auto& d : reader.diagnostics()) {
    if (d.severity == Diagnostic::Severity::error) errors.push_back(d);
    else loaded.warnings.push_back(d);
  }
  if (!errors.empty()) {
    // Sorted by position so the messages read top to bottom like the file.
    std::stable_sort(errors.begin(), errors.end(), [](const Diagnostic& a, const Diagnostic& b) {
      return std::tie(a.line, a.column) < std::tie(b.line, b.column);
    });
    errors.insert(errors.end(), loaded.warnings.begin(), loaded.warnings.end());
    throw SceneError(std::move(errors));
  }
  return loaded;
}

LoadedScene load_scene(const std::filesystem::path& file) {
  const std::string label = file.string();
  const auto refuse = [&](const std::string& message) {
    Diagnostic d;
    d.file = label;
    d.message = message;
    throw SceneError({d});
  };
  std::error_code ec;
  // Only a regular file of plausible size is read: a FIFO or a device would block or never end.
  if (!std::filesystem::exists(file, ec)) refuse(ec ? "cannot be reached: " + ec.message() : "no such scene file");
  if (!std::filesystem::is_regular_file(file, ec))
    refuse("not a regular file; a scene is a YAML text file, not a folder, FIFO or device");
  if (std::filesystem::file_size(file, ec) > kMaxSceneBytes)
    refuse(std::to_string(std::filesystem::file_size(file, ec) >> 10) +
           " KB; a scene is a few kilobytes of YAML, at most 1 MB (meshes and trajectories go in their own files)");
  std::ifstream in(file, std::ios::binary);
  if (!in) refuse("cannot read the scene file");
  std::ostringstream text;
  text << in.rdbuf();
  const auto absolute = std::filesystem::absolute(file).lexically_normal();
  LoadedScene loaded = parse_scene(text.str(), label, absolute.parent_path());
  loaded.scene.source = absolute;
  return loaded;
}

// ---- names --------------------------------------------------------------------------------------

const char* to_string(MeshSource v) {
  switch (v) {
    case MeshSource::file: return "file";
    case MeshSource::volume: return "volume";
    case MeshSource::phantom: return "phantom";
    case MeshSource::generated: return "generate";
  }
  return "?";
}
const char* to_string(ElementType v) { return name_of(kElements, v); }
const char* to_string(GeneratedShape v) { return name_of(kShapes, v); }
const char* to_string(SmoothingFilter v) { return name_of(kFilters, v); }
const char* to_string(Effect v) { return name_of(kEffects, v); }  // the tables: effects_reader.cc
const char* to_string(TimeIntegrator v) { return name_of(kIntegrators, v); }
const char* to_string(PressureVolumeLaw v) { return name_of(kLaws, v); }

}  // namespace fetouch::config

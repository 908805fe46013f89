// The `boundary` section of a scene: regions, their selectors and supports per component.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "config/plausible.h"
#include "config/section_readers.h"

namespace fetouch::config {
namespace detail {
namespace {

const Choices<BoundaryType> kBoundaryTypes{{"fixed", BoundaryType::fixed},
                                           {"traction", BoundaryType::traction},
                                           {"symmetry", BoundaryType::symmetry},
                                           {"roller", BoundaryType::roller}};

// ---- boundary -----------------------------------------------------------------------------------

void read_selector(MapView& parent, Selector& out) {
  const Entry e = parent.entry("select");
  Reader& reader = parent.reader();
  MapView map(reader, e.value, e.path, e.key_mark, {"box", "physical_group", "plane"});
  if (!map.valid()) return;
  const int kinds = int(map.has("box")) + int(map.has("physical_group")) + int(map.has("plane"));
  if (kinds != 1) {
    reader.error(map.mark(), map.path(),
                 kinds == 0 ? "select the region by one of box, physical_group or plane"
                            : "select the region by only one of box, physical_group or plane");
    return;
  }
  if (map.has("physical_group")) {
    out.kind = SelectorKind::physical_group;
    if (map.text("physical_group", out.physical_group) && out.physical_group.empty())
      reader.error(map.entry("physical_group").value_mark, map.child_path("physical_group"),
                   "expected the name of a physical group of the mesh");
  } else if (map.has("box")) {
    out.kind = SelectorKind::box;
    const Entry box_entry = map.entry("box");
    MapView box(reader, box_entry.value, box_entry.path, box_entry.key_mark, {"min", "max"});
    if (box.valid() && box.vec3("min", out.box_min, Need::required) &&
        box.vec3("max", out.box_max, Need::required)) {
      for (int i = 0; i < 3; ++i)
        if (!(out.box_min[i] < out.box_max[i])) {
          reader.error(box.entry("max").value_mark, box.child_path("max"),
                       "each component of max must exceed min's; component " + std::to_string(i) +
                           " has min " + format_number(out.box_min[i]) + " and max " +
                           format_number(out.box_max[i]));
          break;
        }
    }
  } else {
    out.kind = SelectorKind::plane;
    const Entry plane_entry = map.entry("plane");
    MapView plane(reader, plane_entry.value, plane_entry.path, plane_entry.key_mark,
                  {"point", "normal", "tolerance_m"});
    if (!plane.valid()) return;
    plane.vec3("point", out.plane_point, Need::required);
    if (plane.vec3("normal", out.plane_normal, Need::required)) {
      const auto& n = out.plane_normal;
      const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (length == 0)
        reader.error(plane.entry("normal").value_mark, plane.child_path("normal"),
                     "the normal must not be the zero vector");
      else
        for (double& c : out.plane_normal) c /= length;
    }
    plane.number("tolerance_m", out.plane_tolerance_m, plausible::plane_tolerance_m);
  }
}

// `components: [x, z]`: a non-empty list of distinct axes.
bool read_components(MapView& map, std::array<bool, 3>& out) {
  const Entry e = map.entry("components");
  Reader& reader = map.reader();
  const std::string accepted = "a non-empty list of distinct axes among x, y and z, e.g. [x, z]";
  if (!e.value.IsSequence() || e.value.size() == 0) {
    reader.error(e.value_mark, e.path,
                 (e.value.IsSequence() ? std::string("the list is empty") : "got " + detail::describe_node(e.value)) +
                     "; expected " + accepted);
    return false;
  }
  std::array<bool, 3> components{false, false, false};
  for (size_t i = 0; i < e.value.size(); ++i) {
    const YAML::Node item = e.value[i];
    const std::string name = item.IsScalar() ? item.Scalar() : "";
    const int axis = name == "x" ? 0 : name == "y" ? 1 : name == "z" ? 2 : -1;
    const std::string path = e.path + "[" + std::to_string(i) + "]";
    if (axis < 0) {
      reader.error(item.Mark(), path,
                   (item.IsScalar() ? "unknown axis '" + name + "'" : "got " + detail::describe_node(item)) +
                       "; expected " + accepted);
      return false;
    }
    if (components[axis]) {
      reader.error(item.Mark(), path, "axis " + name + " is listed twice; expected " + accepted);
      return false;
    }
    components[axis] = true;
  }
  out = components;
  return true;
}

// symmetry and roller without `components`: the axis of an axis-aligned plane selector's normal.
void normal_components(Reader& reader, MapView& map, BoundaryRegion& region) {
  const auto& n = region.select.plane_normal;
  for (int axis = 0; axis < 3 && region.select.kind == SelectorKind::plane; ++axis)
    if (std::abs(std::abs(n[axis]) - 1) < 1e-9) {
      region.components = {axis == 0, axis == 1, axis == 2};
      return;
    }
  reader.error(map.mark(), map.path(),
               std::string("a ") + to_string(region.type) +
                   " region holds the displacement along its normal: select it by a plane whose normal is "
                   "the x, y or z axis, or name the held axes with components: [x, y or z]");
}

}  // namespace

void read_boundary(MapView& scene, std::vector<BoundaryRegion>& out) {
  const Entry e = scene.entry("boundary");
  Reader& reader = scene.reader();
  if (e.value.IsNull()) return;
  if (!e.value.IsSequence()) {
    reader.error(e.value_mark, e.path,
                 "expected a list of regions (- name: ..., type: fixed, select: ...), got " +
                     detail::describe_node(e.value));
    return;
  }
  std::set<std::string> names;
  for (size_t i = 0; i < e.value.size(); ++i) {
    const YAML::Node item = e.value[i];
    const std::string path = e.path + "[" + std::to_string(i) + "]";
    MapView map(reader, item, path, item.Mark(), {"name", "type", "select", "traction_pa", "components"});
    if (!map.valid()) continue;
    BoundaryRegion region;
    region.where = {map.mark().line + 1, map.mark().column + 1};
    if (map.text("name", region.name, Need::required)) {
      if (region.name.empty())
        reader.error(map.entry("name").value_mark, map.child_path("name"), "a name must not be empty");
      else if (!names.insert(region.name).second)
        reader.error(map.entry("name").value_mark, map.child_path("name"),
                     "boundary region name '" + region.name + "' is used twice; names must be unique");
    }
    const bool typed = map.choice("type", region.type, kBoundaryTypes, Need::required);
    if (typed) {
      if (region.type == BoundaryType::traction) {
        map.vec3("traction_pa", region.traction_pa, Need::required);
        reject_keys(map, {"components"}, "by a traction region");
      } else {
        reject_keys(map, {"traction_pa"}, std::string("by a ") + to_string(region.type) + " region");
      }
    }
    map.require("select", "a box, a physical_group or a plane");
    if (map.has("select")) read_selector(map, region.select);
    if (typed && region.type != BoundaryType::traction) {
      if (map.has("components")) read_components(map, region.components);
      else if (region.type != BoundaryType::fixed && map.has("select")) normal_components(reader, map, region);
    }
    out.push_back(region);
  }
}

}  // namespace detail

using namespace detail;

const char* to_string(BoundaryType v) { return name_of(kBoundaryTypes, v); }

const char* to_string(SelectorKind v) {
  switch (v) {
    case SelectorKind::box: return "box";
    case SelectorKind::physical_group: return "physical_group";
    case SelectorKind::plane: return "plane";
  }
  return "?";
}

}  // namespace fetouch::config

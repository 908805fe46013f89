// The scene's materials: `material:` (the whole tissue, or every region `materials:` leaves out) and
// `materials:` (a material per region, keyed by the region's name or material id).
#include <algorithm>
#include <string>
#include <vector>

#include "config/plausible.h"
#include "config/section_readers.h"
#include "config/yaml_reader.h"

namespace fetouch::config {

namespace detail {
namespace {

const Choices<MaterialModel> kModels{
    {"linear_elastic", MaterialModel::linear_elastic},
    {"saint_venant_kirchhoff", MaterialModel::saint_venant_kirchhoff},
    {"neo_hookean", MaterialModel::neo_hookean},
    {"neo_hookean_incompressible", MaterialModel::neo_hookean_incompressible},
    {"mooney_rivlin", MaterialModel::mooney_rivlin}};

void read_material(Reader& reader, const Entry& e, Material& out) {
  MapView map(reader, e.value, e.path, e.key_mark,
              {"model", "youngs_modulus_pa", "poisson_ratio", "c10_pa", "c01_pa", "bulk_modulus_pa",
               "density_kg_per_m3"});
  if (!map.valid()) return;
  map.number("density_kg_per_m3", out.density_kg_per_m3, plausible::density_kg_per_m3);
  if (!map.choice("model", out.model, kModels, Need::required)) return;
  if (out.model == MaterialModel::mooney_rivlin) {
    reject_keys(map, {"youngs_modulus_pa", "poisson_ratio"},
                "by mooney_rivlin (it takes c10_pa, c01_pa and bulk_modulus_pa)");
    map.number("c10_pa", out.c10_pa, plausible::hyperelastic_constant_pa, Need::required);
    map.number("c01_pa", out.c01_pa, {0, 1e9, false, false, "0 to 1 GPa"}, Need::required);
    map.number("bulk_modulus_pa", out.bulk_modulus_pa, plausible::bulk_modulus_pa, Need::required);
  } else {
    reject_keys(map, {"c10_pa", "c01_pa", "bulk_modulus_pa"},
                std::string("by ") + name_of(kModels, out.model) +
                    " (it takes youngs_modulus_pa and poisson_ratio)");
    map.number("youngs_modulus_pa", out.youngs_modulus_pa, plausible::modulus_pa, Need::required);
    // The bounds of an isotropic solid: K > 0 and mu > 0 with E > 0 give -1 < nu < 0.5.
    map.number("poisson_ratio", out.poisson_ratio, {-1, 0.5, true, true}, Need::required);
  }
}

}  // namespace

void read_materials(MapView& scene, Scene& out) {
  Reader& reader = scene.reader();
  out.material_given = scene.has("material");
  if (out.material_given) read_material(reader, scene.entry("material"), out.material);
  if (!scene.has("materials")) {
    if (!out.material_given)
      scene.require("material", "the tissue's constitutive model and parameters (or `materials:`, one per region)");
    return;
  }
  const Entry e = scene.entry("materials");
  if (!e.value.IsMap() || e.value.size() == 0) {
    reader.error(e.value_mark, e.path,
                 "expected a mapping of region names (or material ids) to materials, got " + describe_node(e.value));
    return;
  }
  // The keys are the mesh's region names: any word (MapView still reports duplicates).
  std::vector<std::string> regions;
  for (auto it = e.value.begin(); it != e.value.end(); ++it)
    if (it->first.IsScalar()) regions.push_back(it->first.Scalar());
  MapView map(reader, e.value, e.path, e.key_mark, regions);
  if (!map.valid()) return;
  std::vector<std::string> seen;
  for (const std::string& region : regions) {
    if (std::find(seen.begin(), seen.end(), region) != seen.end()) continue;  // a duplicate, reported
    seen.push_back(region);
    const Entry entry = map.entry(region);
    RegionMaterial m;
    m.region = region;
    m.where = {static_cast<int>(entry.key_mark.line) + 1, static_cast<int>(entry.key_mark.column) + 1};
    read_material(reader, entry, m.material);
    out.materials.push_back(m);
  }
  if (!out.material_given && !out.materials.empty()) out.material = out.materials.front().material;
}

}  // namespace detail

const char* to_string(MaterialModel v) { return detail::name_of(detail::kModels, v); }

}  // namespace fetouch::config

#include "fem/tissue_mesh_builder.h"

#include "fem/vtu_mesh.h"
#include "meshes/mesh_file_checks.h"

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/grid_in.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/grid/manifold_lib.h>

#include <gmsh.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <limits>
#include <stdexcept>

namespace fetouch::fem {

namespace {

using dealii::Point;
using dealii::Triangulation;

bool wants_simplex(config::ElementType element) {
  return element == config::ElementType::p1 || element == config::ElementType::p2;
}

// Names of the physical groups of a Gmsh file of dimension `dim` (2: boundary regions, 3: volume
// regions), keyed by name; deal.II's read_msh turns the tags into boundary and material ids but drops
// the names.
std::map<std::string, unsigned int> gmsh_groups(const std::string& file, int dim) {
  std::map<std::string, unsigned int> names;
  gmsh::initialize();
  gmsh::option::setNumber("General.Terminal", 0);
  try {
    gmsh::open(file);
    gmsh::vectorpair groups;
    gmsh::model::getPhysicalGroups(groups, dim);
    for (const auto& [group_dim, tag] : groups) {
      std::string name;
      gmsh::model::getPhysicalName(group_dim, tag, name);
      names[name.empty() ? "group " + std::to_string(tag) : name] = static_cast<unsigned int>(tag);
    }
  } catch (...) {
    gmsh::finalize();
    throw std::runtime_error(file + ": Gmsh could not read its physical groups");
  }
  gmsh::finalize();
  return names;
}

// deal.II cannot hold a boundary id on a face inside the volume, so a .msh whose surface groups
// include a mesher's interfaces between regions (`fetouch mesh --regions`) is read from a copy
// without them: a surface entity every triangle of which two tetrahedra share goes, with its
// groups. Returns the file to read (the given one when nothing is inner or Gmsh cannot tell, which
// leaves the errors to deal.II's reader).
static std::string without_inner_surfaces(const std::string& file) {
  std::string copy;
  gmsh::initialize();
  gmsh::option::setNumber("General.Terminal", 0);
  try {
    gmsh::open(file);
    std::vector<int> types;
    std::vector<std::vector<std::size_t>> tags, nodes;
    std::map<std::array<std::size_t, 3>, int> held;
    gmsh::model::mesh::getElements(types, tags, nodes, 3);
    for (std::size_t t = 0; t < types.size(); ++t) {
      if (types[t] != 4) continue;  // 4-node tetrahedra
      const auto& n = nodes[t];
      for (std::size_t e = 0; e + 3 < n.size(); e += 4)
        for (int f = 0; f < 4; ++f) {
          std::array<std::size_t, 3> face{n[e + (f + 1) % 4], n[e + (f + 2) % 4], n[e + (f + 3) % 4]};
          std::sort(face.begin(), face.end());
          ++held[face];
        }
    }
    gmsh::vectorpair surfaces, inner;
    gmsh::model::getEntities(surfaces, 2);
    for (const auto& surface : surfaces) {
      gmsh::model::mesh::getElements(types, tags, nodes, 2, surface.second);
      bool all_inner = !types.empty();
      for (std::size_t t = 0; t < types.size() && all_inner; ++t) {
        if (types[t] != 2) all_inner = false;  // 3-node triangles only
        const auto& n = nodes[t];
        for (std::size_t e = 0; e + 2 < n.size() && all_inner; e += 3) {
          std::array<std::size_t, 3> face{n[e], n[e + 1], n[e + 2]};
          std::sort(face.begin(), face.end());
          const auto it = held.find(face);
          all_inner = it != held.end() && it->second > 1;
        }
      }
      if (all_inner) inner.push_back(surface);
    }
    if (!inner.empty()) {
      gmsh::vectorpair groups, drop;
      gmsh::model::getPhysicalGroups(groups, 2);
      for (const auto& group : groups) {
        std::vector<int> entities;
        gmsh::model::getEntitiesForPhysicalGroup(2, group.second, entities);
        if (std::any_of(entities.begin(), entities.end(), [&](int e) {
              return std::find(inner.begin(), inner.end(), std::make_pair(2, e)) != inner.end();
            }))
          drop.push_back(group);
      }
      gmsh::model::removeEntities(inner);
      try {  // Gmsh may have dropped a group with its last entity already
        gmsh::model::removePhysicalGroups(drop);
      } catch (const std::string&) {
      }
      copy = (std::filesystem::temp_directory_path() /
              ("fetouch-" + std::to_string(::getpid()) + "-" + std::filesystem::path(file).filename().string()))
                 .string();
      gmsh::write(copy);
    }
  } catch (...) {  // Gmsh could not read it: deal.II's reader says why
    copy.clear();
  }
  gmsh::finalize();
  return copy.empty() ? file : copy;
}

// deal.II's exception text is a page (condition, backtrace); users need its "Additional information".
std::string short_message(const std::exception& e) {
  std::string text = e.what();
  const std::string marker = "Additional information:";
  auto start = text.find(marker);
  if (start == std::string::npos) return text;
  start += marker.size();
  auto end = text.find("Stacktrace", start);
  std::string info = text.substr(start, end == std::string::npos ? std::string::npos : end - start);
  std::string collapsed;
  for (char c : info) {
    if (c == '\n' || c == '\t') c = ' ';
    if (c == ' ' && (collapsed.empty() || collapsed.back() == ' ')) continue;
    collapsed += c;
  }
  while (!collapsed.empty() && (collapsed.back() == ' ' || collapsed.back() == '-'))
    collapsed.pop_back();
  return collapsed;
}

// Boundary ids from geometry, the same for hexahedra and tetrahedra (deal.II 9.4 does not colorize
// simplex boxes): box faces 0..5 = xmin, xmax, ymin, ymax, zmin, zmax; ball 0; shell inner 0, outer 1.
void name_boundaries(const config::GeneratedMesh& g, Triangulation<3>& tria) {
  for (const auto& cell : tria.active_cell_iterators())
    for (const auto f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary()) continue;
      const Point<3> c = cell->face(f)->center();
      unsigned int id = 0;
      if (g.shape == config::GeneratedShape::box) {
        double best = std::numeric_limits<double>::max();
        for (unsigned int d = 0; d < 3; ++d) {
          if (std::abs(c[d]) < best) best = std::abs(c[d]), id = 2 * d;
          if (std::abs(c[d] - g.size_m[d]) < best) best = std::abs(c[d] - g.size_m[d]), id = 2 * d + 1;
        }
      } else if (g.shape == config::GeneratedShape::shell) {
        // By the face's farthest vertex: the shell's own vertices lie on its spheres, while a
        // flattened face's centre (and a vertex the conversion to tetrahedra adds there) lies well
        // inside its sphere on a coarse shell, below the middle radius for a thin one.
        double farthest = 0;
        for (const unsigned int v : cell->face(f)->vertex_indices()) farthest = std::max(farthest, cell->face(f)->vertex(v).norm());
        id = farthest < 0.5 * (g.inner_radius_m + g.radius_m) ? 0 : 1;
      }
      cell->face(f)->set_boundary_id(dealii::types::boundary_id(id));
    }
}

void generate(const config::GeneratedMesh& g, bool simplex, Triangulation<3>& tria,
              std::map<std::string, unsigned int>& names) {
  switch (g.shape) {
    case config::GeneratedShape::box: {
      // Cells roughly cubic: the shortest edge gets 2^refinements cells, the others in proportion.
      const double shortest = std::min({g.size_m[0], g.size_m[1], g.size_m[2]});
      std::vector<unsigned int> repetitions(3);
      for (int d = 0; d < 3; ++d)
        repetitions[d] = std::max(1u, static_cast<unsigned int>(std::lround(
                                          g.size_m[d] / shortest * (1u << g.refinements))));
      const Point<3> low(0, 0, 0), high(g.size_m[0], g.size_m[1], g.size_m[2]);
      if (simplex)
        dealii::GridGenerator::subdivided_hyper_rectangle_with_simplices(tria, repetitions, low, high);
      else
        dealii::GridGenerator::subdivided_hyper_rectangle(tria, repetitions, low, high);
      name_boundaries(g, tria);
      const char* faces[] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
      for (unsigned int i = 0; i < 6; ++i) names[faces[i]] = i;
      return;
    }
    case config::GeneratedShape::ball:
    case config::GeneratedShape::shell: {
      Triangulation<3> hex;
      if (g.shape == config::GeneratedShape::ball) {
        dealii::GridGenerator::hyper_ball_balanced(hex, Point<3>(), g.radius_m);
        names["surface"] = 0;
      } else {
        dealii::GridGenerator::hyper_shell(hex, Point<3>(), g.inner_radius_m, g.radius_m, 12);
        names["inner"] = 0;
        names["outer"] = 1;
      }
      // Refinement follows the spherical manifolds; the result is then frozen as straight-sided
      // cells, so that hexahedral and tetrahedral versions have the same vertices.
      hex.refine_global(static_cast<unsigned int>(std::max(0, g.refinements - 1)));
      Triangulation<3> flat;
      dealii::GridGenerator::flatten_triangulation(hex, flat);
      if (simplex)
        dealii::GridGenerator::convert_hypercube_to_simplex_mesh(flat, tria);
      else
        tria.copy_triangulation(flat);
      name_boundaries(g, tria);
      return;
    }
  }
}

}  // namespace

TissueMeshInfo build_tissue_mesh(const config::MeshSpec& spec, Triangulation<3>& tria) {
  tria.clear();
  TissueMeshInfo info;
  std::map<unsigned int, std::string> volume_names;  // by material id
  const bool simplex = wants_simplex(spec.element);
  switch (spec.source) {
    case config::MeshSource::generated:
      try {
        generate(spec.generated, simplex, tria, info.boundary_ids);
      } catch (const std::exception& e) {
        throw std::runtime_error("deal.II could not generate the mesh: " + short_message(e));
      }
      break;
    case config::MeshSource::file: {
      const std::string file = spec.path.string();
      meshes::check_mesh_file(spec.path);
      if (spec.path.extension() == ".vtu") {
        info.boundary_ids = read_vtu_mesh(file, tria, &volume_names);
        break;
      }
      if (spec.path.extension() != ".msh")
        throw std::runtime_error(file + ": the solver reads Gmsh .msh and VTK .vtu meshes");
      dealii::GridIn<3> in;  // check_mesh_file made sure it is a mesh, not a .geo script
      in.attach_triangulation(tria);
      const auto unreadable = [&file](const std::string& why) {
        try {
          gmsh::finalize();  // deal.II's reader initialised Gmsh and did not get to finalise it
        } catch (...) {
        }
        return std::runtime_error(file + ": deal.II could not read it: " + why);
      };
      const std::string readable = without_inner_surfaces(file);
      struct Remove {  // the copy, whatever happens
        std::string path;
        ~Remove() {
          if (!path.empty()) std::filesystem::remove(path);
        }
      } remove{readable != file ? readable : std::string()};
      try {
        in.read_msh(readable);
      } catch (const std::exception& e) {
        throw unreadable(short_message(e));
      } catch (const std::string& gmsh_error) {  // what Gmsh's API throws
        throw unreadable(gmsh_error);
      } catch (...) {
        throw unreadable("Gmsh failed");
      }
      if (tria.n_active_cells() == 0) throw std::runtime_error(file + ": the mesh has no volume cells");
      info.boundary_ids = gmsh_groups(readable, 2);
      for (const auto& [name, tag] : gmsh_groups(file, 3)) volume_names[tag] = name;
      break;
    }
    case config::MeshSource::volume:
      throw std::runtime_error(spec.path.string() +
                               ": a volume must be meshed first (fetouch mesh VOLUME -o MESH)");
    case config::MeshSource::phantom:
      throw std::runtime_error("the synthetic phantom must be meshed first (the app does: app/scene_mesh.h)");
  }

  if (spec.source == config::MeshSource::file) {
    double low[3] = {1e300, 1e300, 1e300}, high[3] = {-1e300, -1e300, -1e300};
    for (const auto& v : tria.get_vertices())
      for (int d = 0; d < 3; ++d) low[d] = std::min(low[d], v[d]), high[d] = std::max(high[d], v[d]);
    if (tria.n_vertices() == 0 || std::any_of(tria.get_vertices().begin(), tria.get_vertices().end(),
                                              [](const Point<3>& v) { return !(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])); }))
      throw std::runtime_error(spec.path.string() + ": a vertex has a coordinate that is not a finite number");
    meshes::check_mesh_extent(spec.path.string(), low, high);
  }
  info.simplex = tria.all_reference_cells_are_simplex();
  if (simplex != info.simplex)
    throw std::runtime_error(std::string("element ") + config::to_string(spec.element) + " needs " +
                             (simplex ? "tetrahedra" : "hexahedra") + " but the mesh has " +
                             (info.simplex ? "tetrahedra" : "hexahedra or mixed cells"));
  info.cells = tria.n_active_cells();
  info.vertices = tria.n_used_vertices();
  // cell->measure() is exact for tetrahedra and trilinear hexahedra; GridTools::volume() would need a
  // mapping suited to the reference cell (its default, MappingQ1, fails on simplices).
  info.volume_m3 = 0;
  std::map<unsigned int, TissueMeshInfo::Region> regions;
  for (const auto& cell : tria.active_cell_iterators()) {
    const double volume = cell->measure();
    info.volume_m3 += volume;
    TissueMeshInfo::Region& region = regions[cell->material_id()];
    ++region.cells;
    region.volume_m3 += volume;
  }
  for (auto& [id, region] : regions) {
    region.material_id = id;
    if (const auto name = volume_names.find(id); name != volume_names.end()) region.name = name->second;
    info.regions.push_back(region);
  }
  info.min_diameter_m = dealii::GridTools::minimal_cell_diameter(tria);
  info.max_diameter_m = dealii::GridTools::maximal_cell_diameter(tria);
  return info;
}

const TissueMeshInfo::Region* find_region(const TissueMeshInfo& mesh, const std::string& name) {
  for (const auto& region : mesh.regions)
    if (name == region.name || name == std::to_string(region.material_id)) return &region;
  return nullptr;
}

std::string describe_region(const TissueMeshInfo::Region& region) {
  const std::string id = "id " + std::to_string(region.material_id);
  return region.name.empty() ? id : region.name + " (" + id + ")";
}

RegionMaterials assign_region_materials(const config::Scene& scene, const TissueMeshInfo& mesh) {
  RegionMaterials out;
  const std::string file = scene.source.string();
  const auto problem = [&](const config::SourceLocation& where, const std::string& key, const std::string& message) {
    config::Diagnostic d;
    d.file = file, d.line = where.line, d.column = where.column, d.key = key, d.message = message;
    out.problems.push_back(d);
  };
  std::string listed;
  std::vector<std::string> names;
  for (const auto& region : mesh.regions) {
    listed += (listed.empty() ? "" : ", ") + describe_region(region);
    names.push_back(region.name.empty() ? std::to_string(region.material_id) : region.name);
  }
  for (std::size_t i = 0; i < scene.materials.size(); ++i) {
    const config::RegionMaterial& m = scene.materials[i];
    if (const TissueMeshInfo::Region* region = find_region(mesh, m.region)) {
      if (!out.of_region.count(region->material_id)) out.of_region[region->material_id] = static_cast<int>(i);
      continue;
    }
    std::string message = "the mesh has no region '" + m.region + "'";
    const std::string suggestion = config::closest_match(m.region, names);
    if (!suggestion.empty()) message += "; did you mean '" + suggestion + "'?";
    problem(m.where, "materials." + m.region, message + " (its regions: " + listed + ")");
  }
  for (const auto& region : mesh.regions) {
    if (out.of_region.count(region.material_id)) continue;
    if (scene.material_given) {
      out.of_region[region.material_id] = -1;
      continue;
    }
    const config::SourceLocation where = scene.materials.empty() ? config::SourceLocation{} : scene.materials.front().where;
    problem(where, "materials",
            "region " + describe_region(region) + " (" + std::to_string(region.cells) +
                " cells) has no material: name it under materials:, or give material: for every region not named");
  }
  return out;
}

TissueMeshInfo inspect_tissue_mesh(const config::MeshSpec& spec) {
  Triangulation<3> tria;
  return build_tissue_mesh(spec, tria);
}

}  // namespace fetouch::fem

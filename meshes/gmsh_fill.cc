// Gmsh fills a surface with tetrahedra (meshes/gmsh_fill.h).
#include "meshes/gmsh_fill.h"

#include "meshes/gmsh_session.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <regex>
#include <unistd.h>
#include <stdexcept>

namespace fetouch::meshes {

namespace {

// Where Gmsh's log names a place ("... at point (x,y,z)", "... near (x,y,z)"), in millimetres.
std::string place_in(const std::vector<std::string>& log) {
  static const std::regex point(R"((?:at point|near|point)\s*\(\s*([-+0-9.eE]+)\s*,\s*([-+0-9.eE]+)\s*,\s*([-+0-9.eE]+)\s*\))");
  for (auto line = log.rbegin(); line != log.rend(); ++line) {
    std::smatch m;
    if (std::regex_search(*line, m, point) && std::isfinite(std::strtod(m[1].str().c_str(), nullptr))) {
      char text[160];
      std::snprintf(text, sizeof text, " near (%.1f, %.1f, %.1f) mm", 1e3 * std::strtod(m[1].str().c_str(), nullptr),
                    1e3 * std::strtod(m[2].str().c_str(), nullptr), 1e3 * std::strtod(m[3].str().c_str(), nullptr));
      // "PLC Error:  Two facets intersect at point (...)": the words between the label and the place.
      std::string what = line->substr(0, static_cast<std::size_t>(m.position(0)));
      const auto label = what.rfind(':');
      if (label != std::string::npos) what = what.substr(label + 1);
      what.erase(0, what.find_first_not_of(' '));
      what.erase(what.find_last_not_of(' ') + 1);
      return ": " + (what.empty() ? std::string("the surface") : what) + text;
    }
  }
  return "";
}

// Gmsh's last error lines (its exception says only which step failed).
std::string errors_in(const std::vector<std::string>& log) {
  std::string out;
  for (const auto& line : log)
    if (line.rfind("Error", 0) == 0 && out.size() < 300) out += (out.empty() ? "" : "; ") + line.substr(line.find(':') + 2);
  return out;
}

// Gmsh's own messages for the length of a fill: its logger (on, then off again however the fill
// ends), and what its mesher prints to the standard output itself (HXT's boundary recovery prints
// the facets that intersect there, even with Gmsh's terminal off): kept out of Fetouch's output (a
// report in JSON goes there) and read for the place of a failure.
class GmshMessages {
 public:
  GmshMessages() {
    gmsh::logger::start();
    std::fflush(stdout);
    // FETOUCH_GMSH_LOG (meshes/gmsh_session.h) shows Gmsh's log: then nothing is captured.
    capture_ = std::getenv("FETOUCH_GMSH_LOG") ? nullptr : std::tmpfile();
    saved_ = capture_ ? ::dup(1) : -1;
    if (saved_ >= 0) ::dup2(::fileno(capture_), 1);
  }
  ~GmshMessages() {
    restore();
    if (capture_) std::fclose(capture_);
    gmsh::logger::stop();
  }
  GmshMessages(const GmshMessages&) = delete;
  GmshMessages& operator=(const GmshMessages&) = delete;

  // The logger's lines, then the printed ones.
  std::vector<std::string> lines() {
    restore();
    std::vector<std::string> out;
    gmsh::logger::get(out);
    if (capture_) {
      std::rewind(capture_);
      char line[512];
      while (std::fgets(line, sizeof line, capture_) && out.size() < 10000) out.emplace_back(line);
    }
    return out;
  }

 private:
  void restore() {
    if (saved_ < 0) return;
    std::fflush(stdout);
    ::dup2(saved_, 1);
    ::close(saved_);
    saved_ = -1;
  }
  std::FILE* capture_ = nullptr;
  int saved_ = -1;
};

// Throws when Gmsh's surface mesh has a triangle twice or an edge not shared by exactly two
// triangles, naming how many and where the first one is (mm).
void check_surface_mesh() {
  std::vector<std::size_t> tags, nodes;
  gmsh::model::mesh::getElementsByType(2, tags, nodes, -1);
  std::map<std::array<std::size_t, 3>, int> faces;
  std::map<std::array<std::size_t, 2>, int> edges;
  for (std::size_t e = 0; e + 2 < nodes.size(); e += 3) {
    std::array<std::size_t, 3> f{nodes[e], nodes[e + 1], nodes[e + 2]};
    for (int k = 0; k < 3; ++k) {
      std::array<std::size_t, 2> edge{f[k], f[(k + 1) % 3]};
      if (edge[0] > edge[1]) std::swap(edge[0], edge[1]);
      ++edges[edge];
    }
    std::sort(f.begin(), f.end());
    ++faces[f];
  }
  long duplicated = 0, bad_edges = 0;
  std::size_t where = 0;
  for (const auto& [f, n] : faces)
    if (n > 1) duplicated += n - 1, where = where ? where : f[0];
  for (const auto& [e, n] : edges)
    if (n != 2) ++bad_edges, where = where ? where : e[0];
  if (duplicated == 0 && bad_edges == 0) return;
  std::vector<double> coordinates, uvw;
  gmsh::model::mesh::getNode(where, coordinates, uvw);
  char text[300];
  std::snprintf(text, sizeof text,
                "its remeshed surface has %ld duplicated triangles and %ld edges not shared by two triangles, the first near "
                "(%.1f, %.1f, %.1f) mm (a fold or a part thinner than the elements)",
                duplicated, bad_edges, 1e3 * coordinates.at(0), 1e3 * coordinates.at(1), 1e3 * coordinates.at(2));
  throw std::runtime_error(text);
}

// Gmsh's tetrahedra and their nodes (metres), each element positively oriented.
void extract_tetrahedra(GmshFill& out) {
  std::vector<std::size_t> mesh_tags, element_tags, element_nodes;  // Gmsh takes non-empty vectors as preallocated
  std::vector<double> all_coordinates, parametric;
  gmsh::model::mesh::getNodes(mesh_tags, all_coordinates, parametric, -1, -1, false, false);
  const std::size_t largest = mesh_tags.empty() ? 0 : *std::max_element(mesh_tags.begin(), mesh_tags.end());
  std::vector<int> index(largest + 1, -1);
  out.nodes_m.clear();
  out.tetrahedra.clear();
  for (std::size_t i = 0; i < mesh_tags.size(); ++i) {
    index[mesh_tags[i]] = static_cast<int>(i);
    out.nodes_m.push_back({all_coordinates[3 * i], all_coordinates[3 * i + 1], all_coordinates[3 * i + 2]});
  }
  gmsh::model::mesh::getElementsByType(4, element_tags, element_nodes, -1);
  if (element_nodes.empty()) throw std::runtime_error("Gmsh made no tetrahedra");
  out.tetrahedra.reserve(element_nodes.size() / 4);
  for (std::size_t e = 0; e < element_nodes.size(); e += 4) {
    Tet t{index.at(element_nodes[e]), index.at(element_nodes[e + 1]), index.at(element_nodes[e + 2]),
          index.at(element_nodes[e + 3])};
    if (tet_signed_volume(out.nodes_m[t[0]], out.nodes_m[t[1]], out.nodes_m[t[2]], out.nodes_m[t[3]]) < 0)
      std::swap(t[2], t[3]);
    out.tetrahedra.push_back(t);
  }
}

}  // namespace

std::vector<FillPath> fill_paths(FillSurface surface) {
  return {{surface, FillMesher::delaunay}, {surface, FillMesher::hxt}};
}

const char* describe(FillSurface surface) {
  switch (surface) {
    case FillSurface::remeshed: return "surface remeshed by Gmsh";
    case FillSurface::as_given: return "surface as extracted";
    case FillSurface::restricted: return "CGAL restricted Delaunay surface";
  }
  return "";
}

std::string describe(FillPath path) {
  return std::string(describe(path.surface)) + (path.mesher == FillMesher::delaunay ? ", Delaunay" : ", HXT");
}

GmshFill gmsh_fill(const std::vector<double>& nodes_mm, const std::vector<std::size_t>& triangles,
                   const MeshingSettings& s, FillPath path) {
  GmshSession session;
  GmshMessages messages;
  GmshFill out;
  std::vector<std::size_t> node_tags(nodes_mm.size() / 3);
  std::vector<double> coordinates(nodes_mm.size());
  for (std::size_t i = 0; i < node_tags.size(); ++i) node_tags[i] = i + 1;
  for (std::size_t i = 0; i < nodes_mm.size(); ++i) coordinates[i] = nodes_mm[i] * 1e-3;  // mm -> m
  std::vector<std::size_t> triangle_nodes(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i) triangle_nodes[i] = triangles[i] + 1;
  const auto add_surface = [&] {
    gmsh::model::add("tissue");
    gmsh::model::addDiscreteEntity(2, 1);
    gmsh::model::mesh::addNodes(2, 1, node_tags, coordinates);
    gmsh::model::mesh::addElementsByType(1, 2, {}, triangle_nodes);
  };
  // The surface is split into patches Gmsh can parametrise and remesh at the target size (the
  // decimated triangles are too uneven for good tetrahedra next to them). No feature angle: the
  // tissue's surface is smooth, and feature curves kept the decimation's folds as creases. A
  // surface Gmsh cannot parametrise is kept as it is.
  std::vector<int> patch_tags{1};
  add_surface();
  if (path.surface == FillSurface::remeshed) {
    try {
      gmsh::model::mesh::classifySurfaces(M_PI, true, true, M_PI);
      gmsh::model::mesh::createGeometry();
      std::vector<std::pair<int, int>> patches;
      gmsh::model::getEntities(patches, 2);
      patch_tags.clear();
      for (const auto& [dim, tag] : patches) patch_tags.push_back(tag);
      out.surface_remeshed = true;
    } catch (const std::string&) {
      gmsh::model::remove();
      add_surface();
    }
  }
  try {
    const int loop = gmsh::model::geo::addSurfaceLoop(patch_tags);
    gmsh::model::geo::addVolume({loop}, 1);
    gmsh::model::geo::synchronize();
  } catch (const std::string& e) {
    throw std::runtime_error("Gmsh could not bound a volume by the surface: " + e + place_in(messages.lines()));
  }
  const double h = s.element_size_mm * 1e-3;
  gmsh::option::setNumber("Mesh.MeshSizeMax", h);
  gmsh::option::setNumber("Mesh.MeshSizeMin", 0.2 * (!s.refine_balls.empty() ? std::min(h, s.refine_size_mm * 1e-3) : h));
  if (!s.refine_balls.empty()) {
    // Finer elements in each ball (where a probe touches), grading to the element size over one
    // more radius; where balls overlap the finest (a Min field; one ball is its own field, as before).
    std::vector<double> fields;
    for (const MeshingSettings::RefineBall& b : s.refine_balls) {
      const int ball = gmsh::model::mesh::field::add("Ball");
      gmsh::model::mesh::field::setNumber(ball, "Radius", b.radius_mm * 1e-3);
      gmsh::model::mesh::field::setNumber(ball, "Thickness", b.radius_mm * 1e-3);
      gmsh::model::mesh::field::setNumber(ball, "VIn", s.refine_size_mm * 1e-3);
      gmsh::model::mesh::field::setNumber(ball, "VOut", h);
      gmsh::model::mesh::field::setNumber(ball, "XCenter", b.center_mm[0] * 1e-3);
      gmsh::model::mesh::field::setNumber(ball, "YCenter", b.center_mm[1] * 1e-3);
      gmsh::model::mesh::field::setNumber(ball, "ZCenter", b.center_mm[2] * 1e-3);
      fields.push_back(ball);
    }
    int background = static_cast<int>(fields.front());
    if (fields.size() > 1) {
      background = gmsh::model::mesh::field::add("Min");
      gmsh::model::mesh::field::setNumbers(background, "FieldsList", fields);
    }
    gmsh::model::mesh::field::setAsBackgroundMesh(background);
  }
  gmsh::option::setNumber("Mesh.Optimize", 1);
  // The mesher, then the optimiser on every element of quality (gamma) under 0.5: on the phantom's
  // fetus the Delaunay mesher without it left slivers of 1.3 degrees, HXT with the default threshold
  // 9.3; with it, Delaunay 18.5 degrees at 8 mm (2026-11-30).
  gmsh::option::setNumber("Mesh.Algorithm3D", path.mesher == FillMesher::delaunay ? 1 : 10);
  // A restricted Delaunay surface's triangles are good (angles of 25 degrees and more): a threshold
  // of 0.3 (HXT's own) left no sliver the repair cannot mend, and 0.5 took ten times as long on a
  // head (5.6 s against 0.5 s at 8 mm; measured with HXT).
  gmsh::option::setNumber("Mesh.OptimizeThreshold", path.surface == FillSurface::restricted ? 0.3 : 0.5);
  try {
    gmsh::model::mesh::generate(2);
    // HXT ends the process (exit 1, "not handled in Release mode") on a duplicated triangle, which
    // Gmsh's remeshing of a folded surface can leave: the surface is checked before it is filled.
    check_surface_mesh();
    gmsh::model::mesh::generate(3);
    extract_tetrahedra(out);
    // Gmsh's optimisers only where the mesher left elements under the angle asked (on a surface of good
    // triangles it rarely does, and on two million elements they take longer than the mesh; the
    // sliver repair takes the rest).
    double worst = 180;
    for (const Tet& t : out.tetrahedra) worst = std::min(worst, min_dihedral_deg(out.nodes_m, t));
    if (worst < s.min_dihedral_deg) {
      const auto optimising = std::chrono::steady_clock::now();
      // Debian's Gmsh has no Netgen: its own optimiser, then node relocation.
      gmsh::model::mesh::optimize("", false, 2);
      gmsh::model::mesh::optimize("Relocate3D");
      extract_tetrahedra(out);
      out.optimisation_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - optimising).count();
    }
  } catch (const std::string& e) {  // Gmsh's API throws its message as a string
    const auto log = messages.lines();
    const std::string errors = errors_in(log);
    throw std::runtime_error("Gmsh could not fill the surface: " + (errors.empty() ? e : errors) + place_in(log));
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("Gmsh could not fill the surface: ") + e.what());
  }
  return out;
}

}  // namespace fetouch::meshes

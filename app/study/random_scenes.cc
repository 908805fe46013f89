#include "app/study/random_scenes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>

#include "app/output_guard.h"

namespace fetouch::app {

namespace {

// Draws for one scene: enum values in turn over the scene index, numbers from a generator seeded by
// (seed, index), so that scene i is the same whatever other scenes are drawn.
class Draw {
 public:
  Draw(unsigned int seed, int index) : seed_(seed), index_(index), random_(seed * 1000003u + static_cast<unsigned int>(index)) {}
  // Value (index / stride + offset) mod count of a list, the offset fixed per key and seed. A stride
  // turns a value among the scenes that share another's (the element among the scenes of a shape).
  template <class T>
  T turn(const char* key, const std::vector<T>& values, unsigned int stride = 1) {
    unsigned int offset = seed_;
    for (const char* c = key; *c; ++c) offset = offset * 31u + static_cast<unsigned char>(*c);
    return values[(static_cast<unsigned int>(index_) / stride + offset) % values.size()];
  }
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(random_); }
  // Log-uniform in [lo, hi], its edges taken one time in four each.
  double edges(double lo, double hi) {
    const double u = uniform(0, 1);
    if (u < 0.25) return lo;
    if (u > 0.75) return hi;
    return lo * std::pow(hi / lo, uniform(0, 1));
  }
  bool chance(double p) { return uniform(0, 1) < p; }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(random_); }

 private:
  unsigned int seed_;
  int index_;
  std::mt19937 random_;
};

std::string number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", x);
  return text;
}

std::string triple(double x, double y, double z) { return "[" + number(x) + ", " + number(y) + ", " + number(z) + "]"; }

}  // namespace

RandomScene random_scene(unsigned int seed, int index) {
  Draw draw(seed, index);
  RandomScene s;
  char name[64];
  std::snprintf(name, sizeof name, "scene_%u_%03d", seed, index);
  s.name = name;
  std::ostringstream y;
  y << "# Drawn by `fetouch study hard-cases --random` (seed " << seed << ", scene " << index << ").\n";
  y << "name: " << s.name << "\ndescription: a valid scene drawn from the schema\nunits: SI\n";

  // The tissue: a shape, its element, a size its refinement keeps to a few thousand cells.
  const std::string shape = draw.turn<std::string>("shape", {"box", "ball", "shell"});
  const std::string element = draw.turn<std::string>("element", {"p1", "p2", "q1", "q2"}, 3);  // each shape takes each
  s.p1 = element == "p1";
  const bool linear = element == "p1" || element == "q1";
  const int refinements = linear ? draw.integer(0, 2) : draw.integer(0, 1);
  double sx = 0, sy = 0, sz = 0, radius = 0, inner = 0, top = 0, thickness = 0;
  y << "mesh:\n  generate: {shape: " << shape;
  if (shape == "box") {
    sz = draw.uniform(0.02, 0.06), sx = sz * draw.uniform(1, 2.5), sy = sz * draw.uniform(1, 2.5);
    y << ", size_m: " << triple(sx, sy, sz);
    top = sz, thickness = sz;
  } else {
    radius = draw.uniform(0.02, 0.06);
    y << ", radius_m: " << number(radius);
    if (shape == "shell") {
      inner = radius * draw.uniform(0.4, 0.75);
      y << ", inner_radius_m: " << number(inner);
    }
    top = radius, thickness = shape == "shell" ? radius - inner : radius;
  }
  y << ", refinements: " << refinements << "}\n  element: " << element << "\n";

  // The material: every model, its parameters from their ranges.
  const std::string model =
      draw.turn<std::string>("model", {"linear_elastic", "saint_venant_kirchhoff", "neo_hookean", "neo_hookean_incompressible",
                                       "mooney_rivlin"});
  const double density = draw.uniform(900, 1200);
  y << "material:\n  model: " << model << "\n";
  double modulus;  // Young's modulus, or its equivalent 6 (C10 + C01)
  if (model == "mooney_rivlin") {
    const double c10 = draw.edges(200, 2e5), c01 = draw.chance(0.3) ? 0.0 : c10 * draw.uniform(0, 1);
    modulus = 6 * (c10 + c01);
    y << "  c10_pa: " << number(c10) << "\n  c01_pa: " << number(c01) << "\n  bulk_modulus_pa: "
      << number(modulus * draw.edges(1, 100)) << "\n";
  } else {
    modulus = draw.edges(1000, 1e6);
    const double nu = model == "neo_hookean_incompressible" ? draw.turn<double>("nu_incompressible", {0.45, 0.49, 0.4999})
                                                            : draw.turn<double>("nu", {-0.3, 0.0, 0.3, 0.45, 0.49});
    y << "  youngs_modulus_pa: " << number(modulus) << "\n  poisson_ratio: " << number(nu) << "\n";
  }
  y << "  density_kg_per_m3: " << number(density) << "\n";

  // Effects: contact always (probes touch); the others drawn.
  const bool decoupled = model == "neo_hookean_incompressible" || model == "mooney_rivlin";
  // A fluid in the shell (every sixth scene), two times in three, its law in turn.
  const bool cavity = shape == "shell" && draw.turn<int>("cavity", {1, 1, 0}, 6) == 1;
  const bool inertia = draw.chance(0.45);
  y << "effects:\n  - contact\n";
  if (draw.chance(0.4)) y << "  - gravity: {acceleration_m_per_s2: " << triple(0, 0, -9.81 * draw.uniform(0.5, 1)) << "}\n";
  if (inertia) {
    const std::string integrator = draw.turn<std::string>("integrator", {"backward_euler", "newmark", "hht"});
    y << "  - inertia: {integrator: " << integrator;
    if (integrator == "hht") y << ", hht_alpha: " << number(draw.turn<double>("hht_alpha", {-1.0 / 3.0, -0.1, 0.0}));
    y << "}\n";
    if (draw.chance(0.5))
      y << "  - damping: {mass_coefficient_per_s: " << number(draw.chance(0.5) ? 0.0 : draw.uniform(0, 20))
        << ", stiffness_coefficient_s: " << number(draw.chance(0.5) ? 0.0 : draw.uniform(0, 0.01)) << "}\n";
  }
  if (!s.p1 && (decoupled || draw.chance(0.2)) && draw.chance(0.6)) y << "  - incompressibility\n";  // P1: no gain
  if (cavity) {
    const std::string law = draw.turn<std::string>("law", {"linear", "isothermal_gas"}, 6);
    y << "  - cavity: {surface: inner, law: " << law;
    if (law == "isothermal_gas") y << ", initial_pressure_pa: " << number(draw.uniform(0, 2000));
    y << ", bulk_modulus_pa: " << number(draw.edges(1e4, 2.2e9)) << "}\n";
  }

  // Supports that hold the body (every type and selector in turn), and now and then a traction.
  y << "boundary:\n";
  const std::string support = draw.turn<std::string>("support", {"fixed", "fixed", "roller", "symmetry"});
  const std::string selector = draw.turn<std::string>("selector", {"physical_group", "plane", "box"});
  if (shape == "box") {
    if (support == "fixed") {
      y << "  - name: table\n    type: fixed\n    select: ";
      if (selector == "physical_group") y << "{physical_group: zmin}\n";
      else if (selector == "plane") y << "{plane: {point: [0, 0, 0], normal: [0, 0, 1]}}\n";
      else y << "{box: {min: " << triple(-1e-3, -1e-3, -1e-3) << ", max: " << triple(sx + 1e-3, sy + 1e-3, 1e-3) << "}}\n";
    } else {  // a frictionless table and two planes against sliding and turning
      y << "  - name: table\n    type: " << support << "\n    components: [z]\n    select: {physical_group: zmin}\n";
      y << "  - name: side_x\n    type: " << support << "\n    select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}\n";
      y << "  - name: side_y\n    type: " << support << "\n    components: [y]\n    select: {physical_group: ymin}\n";
    }
  } else {
    // The bottom cap of the ball or shell (or the shell's inner surface, unless a fluid fills it).
    const bool inner_surface = shape == "shell" && !cavity && selector == "physical_group";
    y << "  - name: base\n    type: fixed\n    select: ";
    if (inner_surface) y << "{physical_group: inner}\n";
    // The cap below z = -R/4: it holds face centres at every refinement (a coarse ball's flat faces
    // have their centres well inside the sphere).
    else y << "{box: {min: " << triple(-radius, -radius, -radius * 1.01) << ", max: " << triple(radius, radius, -0.25 * radius) << "}}\n";
  }
  if (draw.chance(0.2) && shape == "box")
    y << "  - name: push\n    type: traction\n    traction_pa: " << triple(0, 0.002 * modulus * draw.uniform(-1, 1), 0)
      << "\n    select: {physical_group: xmax}\n";

  // The solver: every linear solver, rates that divide the haptic rate, the accuracy policy on or off.
  const int rate = draw.turn<int>("rate", {10, 20, 25, 50});
  y << "solver:\n  rate_hz: " << rate << "\n  linear_solver: " << draw.turn<std::string>("linear_solver", {"auto", "direct", "cg_amg"})
    << "\n  newton: {line_search: " << draw.turn<std::string>("line_search", {"true", "false"})
    << ", max_load_step_cuts: " << draw.integer(4, 10) << "}\n";
  if (draw.chance(0.25)) y << "  accuracy: none\n";
  else y << "  accuracy: {position_m: " << number(draw.edges(1e-6, 1e-4)) << ", force_n: " << number(draw.edges(1e-4, 1e-2)) << "}\n";
  y << "  frame_newton_iterations: " << draw.turn<int>("frame_newton_iterations", {0, 4, 10}) << "\n";

  // The haptic loop: every local model and hold, automatic gains, margins at their edges.
  const int probes = draw.chance(0.3) ? 2 : 1;
  const double max_force = draw.edges(1, 10);
  y << "haptics:\n  rate_hz: 1000\n  local_model: " << draw.turn<std::string>("local_model", {"p", "pi", "smith", "pi_smith"})
    << "\n  hold: " << draw.turn<std::string>("hold", {"zoh", "foh"}) << "\n  gains: auto\n  robustness_margin: "
    << number(draw.turn<double>("margin", {0.0, 0.3, 0.6, 0.9})) << "\n  max_force_n: " << number(max_force) << "\n";
  if (probes == 2) y << "  coupling: " << draw.turn<std::string>("coupling", {"true", "false"}) << "\n";
  y << "  passivity: {mode: " << draw.turn<std::string>("passivity", {"on", "observe", "off"})
    << ", controller: " << draw.turn<std::string>("passivity_controller", {"scaling", "hannaford_ryu"}) << "}\n";
  y << "  identification: {enabled: " << draw.turn<std::string>("identification", {"true", "false"})
    << ", forgetting: " << number(draw.turn<double>("forgetting", {0.95, 0.99, 1.0})) << "}\n";

  // Probes: a poke, slide or squeeze on the top, fast or slow; replayed, or an operator's hand pulled along.
  y << "probes:\n";
  const std::string path = draw.turn<std::string>("path", {"poke", "slide", "squeeze"});
  const bool fast = draw.chance(0.5);
  std::string devices;
  for (int p = 0; p < probes; ++p) {
    haptics::PathSettings settings;
    const double offset = probes == 1 ? 0 : (p == 0 ? -0.3 : 0.3) * (shape == "box" ? sx / 2 : radius);
    const double x = (shape == "box" ? sx / 2 : 0) + offset, yy = shape == "box" ? sy / 2 : 0;
    double z = top;
    if (shape != "box") z = std::sqrt(std::max(0.0, radius * radius - offset * offset));
    Eigen::Vector3d normal = shape == "box" ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d(x, 0, z).normalized();
    settings.point = Eigen::Vector3d(x, yy, z);
    settings.normal = normal;
    settings.approach_m = draw.uniform(0.002, 0.01);
    settings.depth_m = thickness * draw.uniform(0.03, 0.25);
    settings.approach_s = draw.uniform(0.1, 0.3);
    settings.press_s = path == "squeeze" ? draw.uniform(0.5, 0.8) : fast ? draw.uniform(0.04, 0.1) : draw.uniform(0.2, 0.5);
    settings.hold_s = draw.uniform(0.1, 0.5);
    settings.release_s = path == "squeeze" ? draw.uniform(0.5, 0.8) : fast ? draw.uniform(0.04, 0.1) : draw.uniform(0.2, 0.5);
    settings.retreat_s = draw.uniform(0.1, 0.2);
    const haptics::PathShape shape_kind = path == "slide" ? haptics::PathShape::slide
                                          : path == "squeeze" ? haptics::PathShape::squeeze
                                                              : haptics::PathShape::poke;
    if (path == "slide") settings.slide_m = Eigen::Vector3d(0, (shape == "box" ? sy : radius) * draw.uniform(0.1, 0.3), 0);
    const std::string file = "probe_" + std::to_string(p) + ".csv";
    s.trajectories.emplace_back(file, haptics::scripted_path(shape_kind, settings));
    s.duration_s = std::max(s.duration_s, s.trajectories.back().second.duration_s());
    const std::string device = draw.turn<std::string>(p == 0 ? "device" : "device_2", {"replay", "operator"});
    devices += (devices.empty() ? "" : "+") + device;
    y << "  - name: probe" << p << "\n    radius_m: " << number(draw.turn<double>("radius", {0.001, 0.003, 0.005, 0.01}))
      << "\n    device:\n      type: " << device << "\n      trajectory: " << file << "\n";
    if (device == "operator" && draw.chance(0.7)) {
      const std::string hand = draw.turn<std::string>("hand_model", {"one_mass", "stylus"});
      y << "      hand: {model: " << hand << ", mass_kg: " << number(draw.uniform(0.02, 0.6))
        << ", stiffness_n_per_m: " << number(draw.uniform(230, 1040)) << ", damping_n_s_per_m: " << number(draw.uniform(0.5, 10));
      if (hand == "stylus")  // Fu & Cavusoglu's ranges for the arm (docs/devices.md)
        y << ", arm_stiffness_n_per_m: " << number(draw.uniform(63, 533)) << ", arm_damping_n_s_per_m: " << number(draw.uniform(3.7, 27.6));
      y << "}\n";
    }
  }
  s.yaml = y.str();
  char summary[256];
  std::snprintf(summary, sizeof summary, "%s %s r%d, %s E %.3g Pa%s%s%s, %d %s probe(s), %s%s", shape.c_str(), element.c_str(),
                refinements, model.c_str(), modulus, inertia ? ", inertia" : "", cavity ? ", cavity" : "",
                s.yaml.find("gravity") != std::string::npos ? ", gravity" : "", probes, devices.c_str(), path.c_str(),
                fast ? " (fast)" : "");
  s.summary = summary;
  return s;
}

std::filesystem::path write_random_scene(const RandomScene& scene, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  for (const auto& [file, trajectory] : scene.trajectories)
    haptics::write_trajectory_csv(trajectory, dir / file, "drawn for " + scene.name);
  write_text_file(dir / "scene.yaml", scene.yaml);
  return dir / "scene.yaml";
}

}  // namespace fetouch::app

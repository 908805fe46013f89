// The scene: everything a Fetouch session needs to know about the tissue, its loads, the solver, the
// haptic loop and the probes, as typed and validated values. docs/scenes.md documents every key.
//
// Units are SI throughout (m, N, s, Pa, kg); key names carry the unit (`radius_m`, `rate_hz`).
// Every path is absolute, resolved against the folder of the scene file that named it.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "config/fetal_pose.h"

namespace fetouch::config {

using Vec3 = std::array<double, 3>;

// Where a value was written (1-based), so later stages can point at the scene when they reject it.
struct SourceLocation {
  int line = 0;
  int column = 0;
};

// ---- mesh ---------------------------------------------------------------------------------------

enum class MeshSource { file, volume, phantom, generated };
enum class ElementType { p1, p2, q1, q2 };  // P: tetrahedra (simplex), Q: hexahedra
enum class GeneratedShape { box, ball, shell };
enum class SmoothingFilter { none, gaussian, median };
// How the segmentation's surface is made before it is filled (docs/meshing.md): CGAL's restricted
// Delaunay surface, or the surface contoured by VTK and remeshed by Gmsh (the mesher before
// revision 3; the anatomy scenes keep it: their figures were measured on it).
// Or (`conforming`, label maps in regions only) every region a subdomain of one CGAL Delaunay mesh,
// its interfaces surfaces of their own (meshes/labeled_mesher.h).
enum class MeshSurface { restricted, contoured, conforming };

// Options for turning an ultrasound volume into a mesh (imaging + meshes pipeline, the same as
// `fetouch mesh`): one of three segmentations (labels of a label map, the fetal pipeline, or
// smoothing + threshold + largest region + closing + hole filling), then meshing.
struct MeshingOptions {
  double target_size_m = 4e-3;
  std::vector<int> labels;          // a label map: these labels are the tissue
  // A label map in regions (`fetouch mesh --regions`): name and labels; their union is `labels`.
  std::vector<std::pair<std::string, std::vector<int>>> regions;
  // `image_regions`: an intensity image made a label map before meshing: label 1 every voxel the
  // image covers (not 0), label 2 the segmentation (threshold etc. below); `regions` then names them
  // {imaged: [1], segmented: [2]} and `labels` stays empty.
  bool regions_from_image = false;
  bool fetus = false;               // the fetal segmentation pipeline
  std::optional<double> threshold;  // intensity; absent: halfway between the 5th and 95th percentiles
  SmoothingFilter smoothing = SmoothingFilter::gaussian;
  double smoothing_sigma_m = 1e-3;  // gaussian only
  int closing_voxels = 2;
  MeshSurface surface = MeshSurface::restricted;
  // Per region element sizes (`conforming` only): region name and size; the others take target_size_m.
  std::vector<std::pair<std::string, double>> sizes_m;
  // Finer elements, refine_size_m, in balls (none: no refinement): the one a scene gives, or one
  // around each probe's trajectory (refine_around_probes: the app finds their centres and radii from
  // the trajectory files before meshing, app/scene_mesh.h).
  struct RefineBall {
    Vec3 center_m{};
    double radius_m = 0;
  };
  std::vector<RefineBall> refine_balls;
  double refine_size_m = 0;
  bool refine_around_probes = false;
};

// A mesh generated from a primitive. Boundary faces of a box are named xmin, xmax, ymin, ymax, zmin,
// zmax; the ball's surface is `surface`; the shell's are `inner` and `outer`.
struct GeneratedMesh {
  GeneratedShape shape = GeneratedShape::box;
  Vec3 size_m{0.1, 0.1, 0.1};  // box edge lengths, the box spans [0, size]
  double radius_m = 0.05;        // ball and shell outer radius, centred at the origin
  double inner_radius_m = 0.03;  // shell only
  int refinements = 2;           // uniform refinements of the coarse primitive
};

// The synthetic fetal phantom (imaging/phantom.h), generated in memory: its label map is the volume.
struct PhantomSource {
  int seed = 1;
  double spacing_m = 1e-3;
  Vec3 fetus_offset_m{0, 0, 0};  // the fetus moved from where the seed puts it
  // How the fetus lies (config/fetal_pose.h); none: where and how the seed puts it (the phantom
  // before poses, kept so that its meshes and figures stay as they were). `lie: random` is drawn
  // from the seed when the scene is read.
  std::optional<FetalPose> pose;
  // The fetus grown to this age (weeks, 14 to 42; imaging/fetal_biometry.h), the uterus with it;
  // none: the seed's fetus, about 16 weeks.
  std::optional<double> gestational_age_weeks;
};

struct MeshSpec {
  MeshSource source = MeshSource::generated;
  std::filesystem::path path;  // file or volume, absolute
  PhantomSource phantom;       // phantom only
  MeshingOptions meshing;      // volume and phantom
  GeneratedMesh generated;     // generated only
  ElementType element = ElementType::p1;
  SourceLocation where;
};

// ---- material -----------------------------------------------------------------------------------

enum class MaterialModel {
  linear_elastic,
  saint_venant_kirchhoff,
  neo_hookean,
  neo_hookean_incompressible,  // decoupled; effect incompressibility: mean dilatation, no locking
  mooney_rivlin
};

struct Material {
  MaterialModel model = MaterialModel::neo_hookean;
  double youngs_modulus_pa = 0;  // all models but mooney_rivlin
  double poisson_ratio = 0;      // all models but mooney_rivlin, in (-1, 0.5)
  double c10_pa = 0;             // mooney_rivlin
  double c01_pa = 0;             // mooney_rivlin
  double bulk_modulus_pa = 0;    // mooney_rivlin
  double density_kg_per_m3 = 1000;
};

// A material for one region of the mesh (`materials:`): a volume physical group of a Gmsh mesh by
// name, or a material id by number (a .vtu's ids, the labels of a mesh made from a label map).
struct RegionMaterial {
  std::string region;
  Material material;
  SourceLocation where;  // the region's key
};

// ---- effects ------------------------------------------------------------------------------------

enum class Effect { elasticity, gravity, inertia, damping, incompressibility, cavity, contact };
enum class TimeIntegrator { backward_euler, newmark, hht };
enum class PressureVolumeLaw { linear, isothermal_gas };

struct Effects {
  std::vector<Effect> listed;  // in the order written; elasticity is always simulated

  Vec3 gravity_m_per_s2{0, 0, -9.81};

  TimeIntegrator integrator = TimeIntegrator::backward_euler;
  double hht_alpha = -0.1;  // in [-1/3, 0]

  double rayleigh_mass_per_s = 0;     // damping C = a M + b K: a
  double rayleigh_stiffness_s = 0;    // b

  std::string cavity_surface;  // physical group of the closed inner surface, or
  std::vector<std::string> cavity_regions;  // the volume regions (names or material ids) it holds
  PressureVolumeLaw cavity_law = PressureVolumeLaw::linear;
  double cavity_initial_pressure_pa = 0;
  double cavity_bulk_modulus_pa = 2.2e9;  // linear law: dp = -K dV / V0 (water)

  bool has(Effect effect) const;
};

// ---- boundary -----------------------------------------------------------------------------------

// fixed: u = 0 on the listed components (all three by default); symmetry and roller: u = 0 along
// the region's normal only, the body slides in the plane (a symmetry plane, a support on rollers).
enum class BoundaryType { fixed, traction, symmetry, roller };
enum class SelectorKind { box, physical_group, plane };

struct Selector {
  SelectorKind kind = SelectorKind::box;
  Vec3 box_min{0, 0, 0};
  Vec3 box_max{0, 0, 0};
  std::string physical_group;
  Vec3 plane_point{0, 0, 0};
  Vec3 plane_normal{0, 0, 1};
  double plane_tolerance_m = 1e-6;
};

struct BoundaryRegion {
  std::string name;
  BoundaryType type = BoundaryType::fixed;
  Selector select;
  Vec3 traction_pa{0, 0, 0};  // traction only
  // fixed, symmetry, roller: the displacement components held at zero (x, y, z). For symmetry and
  // roller, the axis of the plane selector's normal unless `components` names them.
  std::array<bool, 3> components{true, true, true};
  SourceLocation where;
};

// ---- solver -------------------------------------------------------------------------------------

enum class LinearSolver { automatic, direct, cg_amg };

struct Solver {
  double rate_hz = 20;
  double newton_relative_tolerance = 1e-8;
  double newton_absolute_tolerance = 1e-12;
  int newton_max_iterations = 25;
  bool line_search = true;
  int max_load_step_cuts = 8;
  LinearSolver linear_solver = LinearSolver::automatic;
  int direct_max_dofs = 95000;  // automatic: direct up to this size, CG + AMG above (docs/benchmarks.md)
  // The accuracy a frame needs, in the haptic loop's units (0, or `accuracy: none`: off, the
  // residual tolerances alone): each contact's displacement to within position_m (a fifth of a
  // Touch / Omni's nominal 0.055 mm position resolution) and no out-of-balance nodal force over
  // force_n (about 3e-4 of its 3.3 N peak force).
  double accuracy_position_m = 1e-5;
  double accuracy_force_n = 1e-3;
  // The relative error of the condensed compliance W a frame may hand over (the stability region
  // is robust to 30 %): 1e-3 lets most frames update W in the span of the last one's columns.
  double accuracy_compliance = 1e-3;
  // Newton iterations a frame may take before it carries the remainder to the next frame (0: no bound).
  int frame_newton_iterations = 4;
};

// ---- haptics ------------------------------------------------------------------------------------

enum class LocalModelType { p, pi, smith, pi_smith };
enum class HoldType { zoh, foh };
enum class PassivityModeType { off, observe, on };
enum class PassivityControllerType { scaling, hannaford_ryu };

// The passivity layer (haptics/passivity.h): on by default, so a scene that says nothing is
// protected against a hand that closes the loop.
struct Passivity {
  PassivityModeType mode = PassivityModeType::on;
  PassivityControllerType controller = PassivityControllerType::scaling;
  double allowance_j = 2e-5;     // energy a contact may hand the hand before the stiffness is scaled
  double max_step_n = 0.1;       // the controller's force step per tick, at most
  double recovery_per_s = 0.5;   // how fast a scaled stiffness comes back between contacts
};

// On-line identification (haptics/identification.h): the stiffness the hand feels, identified
// from the device's signals and compared at every frame with the condensed stiffness.
struct Identification {
  bool enabled = true;
  double forgetting = 0.99;  // RLS forgetting factor per tick (memory 1 / (1 - f) ticks)
  double bound = 0.25;       // a relative difference above this is reported as a disagreement
};

struct Haptics {
  double rate_hz = 1000;
  LocalModelType local_model = LocalModelType::pi;
  HoldType hold = HoldType::zoh;
  bool automatic_gains = true;
  double proportional_n_per_m = 0;  // Kh, when gains are given
  double integral_n_per_m = 0;      // I in L(z) = Kh + I/(z-1), per tick, when gains are given
  double robustness_margin = 0.3;   // stable for K0 scaled by (1 - m) ... (1 + m)
  double max_force_n = 3.3;
  double max_force_rate_n_per_s = 1000;
  double watchdog_timeout_s = 0.25;
  // The local model's coupling between contacts (the condensed compliance's cross terms): off,
  // each contact renders with its own compliance only, and feels the others one frame late.
  bool coupling = true;
  Passivity passivity;
  Identification identification;
  // A hand the automatic gains must also be stable with (haptics/gain_selection.h): one mass on a
  // spring and a damper to a still target; keys left out take the default hand's (docs/devices.md).
  // Off by default (`design_hand: none`): the proof holds the device still, and the passivity layer
  // answers for the hand (docs/stability.md, section 6, says why it is not on).
  struct DesignHand {
    bool enabled = false;
    double mass_kg = 0.3, stiffness_n_per_m = 300, damping_n_s_per_m = 8;
  } design_hand;

  // Ticks per solver frame, N; valid once the scene has been validated.
  int ratio(const Solver& solver) const;
};

// ---- probes -------------------------------------------------------------------------------------

enum class DeviceType { replay, operator_model, phantom, mouse };

// Something the virtual operator's hand does at a time (haptics::HandEvent; docs/devices.md).
enum class HandEventType { release, grip, tremor, impact };
struct HandEvent {
  HandEventType type = HandEventType::release;
  double at_s = 0;
  double factor = 3, ramp_s = 0.01;               // grip
  double frequency_hz = 10, amplitude_m = 2e-4;   // tremor
  double speed_m_per_s = 0.2;                     // impact
  Vec3 direction{0, 0, -1};                       // tremor, impact
};

// The virtual operator's hand (haptics::HandParameters; docs/devices.md). one_mass: a mass pulled
// to the target by a spring and a damper. stylus: Fu & Cavusoglu's two stages, the handle held by
// the grip (stiffness, damping) to the hand's mass (mass_kg), which the arm pulls to the target.
enum class HandKind { one_mass, stylus };
struct HandModel {
  HandKind model = HandKind::one_mass;
  double mass_kg = 0.3;
  double stiffness_n_per_m = 300;
  double damping_n_s_per_m = 8;
  double handle_mass_kg = 0.045;         // stylus only
  double arm_stiffness_n_per_m = 175;    // stylus only
  double arm_damping_n_s_per_m = 11;     // stylus only
  std::vector<HandEvent> events;
  // The stylus's defaults (the same figures as haptics::stylus_hand()).
  static HandModel stylus() {
    HandModel h;
    h.model = HandKind::stylus;
    h.mass_kg = 0.21, h.stiffness_n_per_m = 575, h.damping_n_s_per_m = 1.3;
    return h;
  }
};

struct Device {
  DeviceType type = DeviceType::replay;
  std::filesystem::path trajectory;  // replay and operator: CSV (t, x, y, z) or a recording (.h5)
  HandModel hand;                    // operator only
  std::string phantom_name;          // phantom only: the HD device name, empty for the default
  std::string library;               // phantom only: libHD.so to load (empty: $FETOUCH_LIBHD or libHD.so)
  // Hardware only: the device frame in the scene (docs/devices.md): the device's axes in the scene
  // frame (the rotation's columns), scene metres per device metre, the device origin's place.
  Vec3 x_axis{1, 0, 0}, y_axis{0, 1, 0}, z_axis{0, 0, 1};
  double scale = 1;
  Vec3 offset_m{0, 0, 0};
  int engage_button = -1;  // -1: engaged from the start
  int clutch_button = -1;  // -1: no clutch
};

struct Probe {
  std::string name;
  Device device;
  double radius_m = 5e-3;
  SourceLocation where;
};

// ---- the scene ----------------------------------------------------------------------------------

struct Scene {
  std::filesystem::path source;  // the scene file, absolute
  std::string text;              // the file's text, kept for recordings
  std::string name;
  std::string description;
  MeshSpec mesh;
  // `material:`, every region's that `materials:` does not name; when only `materials:` is given, its
  // first entry (and material_given is false: every region must then be named).
  Material material;
  bool material_given = true;
  std::vector<RegionMaterial> materials;
  Effects effects;
  std::vector<BoundaryRegion> boundary;
  Solver solver;
  Haptics haptics;
  std::vector<Probe> probes;
};

// Names as written in scene files, for summaries and messages.
const char* to_string(MeshSource);
const char* to_string(ElementType);
const char* to_string(GeneratedShape);
const char* to_string(SmoothingFilter);
const char* to_string(MaterialModel);
const char* to_string(Effect);
const char* to_string(TimeIntegrator);
const char* to_string(PressureVolumeLaw);
const char* to_string(BoundaryType);
const char* to_string(SelectorKind);
const char* to_string(LinearSolver);
const char* to_string(LocalModelType);
const char* to_string(HoldType);
const char* to_string(PassivityModeType);
const char* to_string(PassivityControllerType);
const char* to_string(DeviceType);

}  // namespace fetouch::config

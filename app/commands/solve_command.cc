// `fetouch solve SCENE`: a quasi-static load case on the scene's tissue, as users calibrate and
// verify a tissue model: the scene's supports, tractions and gravity, plus probes pressing with
// given forces (--press), applied in load steps. Writes the deformed mesh (VTU + PVD, for ParaView)
// and a JSON summary: displacements at named points, reactions, Newton's history.
#include <CLI/CLI.hpp>

#include <mpi.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "app/json_writer.h"
#include "app/log.h"
#include "app/output_guard.h"
#include "app/peak_memory.h"
#include "app/scene_mesh.h"
#include "app/scene_rig.h"
#include "app/mpi_session.h"
#include "app/pvd.h"
#include "app/progress.h"
#include "fem/physical_problem.h"
#include "fem/tissue_model.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;

struct SolveOptions {
  std::string scene;
  std::string out;
  std::vector<double> press;   // groups of six: x y z fx fy fz
  std::vector<double> points;  // groups of three
  double radius_m = 0;         // 0: the scene's first probe radius
  int steps = 4;
  double duration_s = 0.5;  // scenes with inertia: the simulated time
  bool json = false;
};

// One time step of a dynamic load case.
struct TimeStep {
  double t = 0;
  int newton_iterations = 0;
  double max_displacement_m = 0;
  dealii::Tensor<1, 3> probe_displacement;  // the first probe's, if any
};

// "owned cells 10, 10, owned dofs 8, 7 by rank: the largest share 0.0 % (cells) and 6.7 % (dofs)
// above the mean".
std::string partition_line(const std::vector<fem::QuasiStaticSolver::Share>& shares) {
  std::ostringstream line;
  double cells_max = 0, cells_sum = 0, dofs_max = 0, dofs_sum = 0;
  std::string cells, dofs;
  for (const auto& share : shares) {
    cells += (cells.empty() ? "" : ", ") + std::to_string(share.cells);
    dofs += (dofs.empty() ? "" : ", ") + std::to_string(share.dofs);
    cells_max = std::max(cells_max, double(share.cells)), cells_sum += share.cells;
    dofs_max = std::max(dofs_max, double(share.dofs)), dofs_sum += share.dofs;
  }
  const double n = static_cast<double>(shares.size());
  line << "owned cells " << cells << ", owned dofs " << dofs << " by rank: the largest share " << std::fixed
       << std::setprecision(1) << 100 * (cells_max * n / cells_sum - 1) << " % (cells) and "
       << 100 * (dofs_max * n / dofs_sum - 1) << " % (dofs) above the mean";
  return line.str();
}

void write_json(std::ostream& out, const SolveOptions& o, const config::Scene& scene, const fem::TissueModel& model,
                const fem::SolveReport& report, double seconds, const std::vector<int>& patches,
                const fs::path& vtu, const fs::path& pvd, const std::vector<TimeStep>& series,
                const std::vector<double>& peak_memory_mb, const std::vector<fem::QuasiStaticSolver::Share>& shares) {
  JsonWriter json(out);
  fem::QuasiStaticSolver& solver = *model.solver;
  json.begin_object();
  json.key("scene").value(scene.source.string());
  json.key("converged").value(report.converged);
  if (!report.converged) json.key("failure").value(report.failure);
  json.key("ranks").value(model.solver->ranks());
  json.key("dofs").value(static_cast<long>(solver.dofs()));
  json.key("cells").value(static_cast<long>(solver.cells()));
  json.key("element_degree").value(model.degree);
  json.key("newton_iterations").value(report.total_iterations);
  json.key("load_step_cuts").value(report.cuts);
  json.key("seconds").value(seconds);
  json.key("peak_memory_mb").begin_array();
  for (double mb : peak_memory_mb) json.value(mb);
  json.end_array();
  json.key("owned_cells").begin_array();
  for (const auto& share : shares) json.value(static_cast<long>(share.cells));
  json.end_array();
  json.key("owned_dofs").begin_array();
  for (const auto& share : shares) json.value(static_cast<long>(share.dofs));
  json.end_array();
  json.key("steps").begin_array();
  for (const auto& step : report.steps) {
    json.begin_object();
    json.key("load_factor").value(step.load_factor);
    json.key("converged").value(step.converged);
    json.key("residuals").begin_array();
    for (double r : step.residuals) json.value(r);
    json.end_array();
    if (!step.converged) json.key("failure").value(step.failure);
    json.end_object();
  }
  json.end_array();
  if (!series.empty()) {
    json.key("dynamic").begin_object();
    json.key("integrator").value(config::to_string(scene.effects.integrator));
    json.key("time_step_s").value(series.size() > 1 ? series[1].t - series[0].t : series[0].t);
    json.key("time_steps").begin_array();
    for (const TimeStep& step : series) {
      json.begin_object();
      json.key("t_s").value(step.t);
      json.key("newton_iterations").value(static_cast<long>(step.newton_iterations));
      json.key("max_displacement_m").value(step.max_displacement_m);
      if (!patches.empty()) {
        json.key("probe_displacement_m").begin_array();
        for (int d = 0; d < 3; ++d) json.value(step.probe_displacement[d]);
        json.end_array();
      }
      json.end_object();
    }
    json.end_array();
    json.end_object();
  }
  if (report.converged) {
    const auto fields = solver.cell_fields();
    json.key("max_displacement_m").value(solver.max_displacement());
    json.key("min_jacobian").value(*std::min_element(fields.jacobian.begin(), fields.jacobian.end()));
    json.key("max_von_mises_pa").value(*std::max_element(fields.von_mises.begin(), fields.von_mises.end()));
    if (scene.effects.has(config::Effect::cavity)) {
      json.key("cavity").begin_object();
      json.key("pressure_pa").value(solver.cavity_pressure());
      json.key("volume_m3").value(solver.cavity_volume());
      json.key("reference_volume_m3").value(solver.cavity_reference_volume());
      json.end_object();
    }
    json.key("reactions_n").begin_object();
    for (const auto& region : scene.boundary) {
      if (region.type == config::BoundaryType::traction) continue;
      const auto r = solver.boundary_force(model.region_ids.at(region.name));
      json.key(region.name).begin_array().value(r[0]).value(r[1]).value(r[2]).end_array();
    }
    json.end_object();
    json.key("probes").begin_array();
    for (size_t p = 0; p < patches.size(); ++p) {
      const auto u = solver.patch_displacement(patches[p]);
      json.begin_object();
      json.key("at_m").begin_array().value(o.press[6 * p]).value(o.press[6 * p + 1]).value(o.press[6 * p + 2]).end_array();
      json.key("force_n").begin_array().value(o.press[6 * p + 3]).value(o.press[6 * p + 4]).value(o.press[6 * p + 5]).end_array();
      json.key("displacement_m").begin_array().value(u[0]).value(u[1]).value(u[2]).end_array();
      json.end_object();
    }
    json.end_array();
    json.key("points").begin_array();
    for (size_t p = 0; p + 2 < o.points.size(); p += 3) {
      const auto u = solver.displacement_at(dealii::Point<3>(o.points[p], o.points[p + 1], o.points[p + 2]));
      json.begin_object();
      json.key("at_m").begin_array().value(o.points[p]).value(o.points[p + 1]).value(o.points[p + 2]).end_array();
      json.key("displacement_m").begin_array().value(u[0]).value(u[1]).value(u[2]).end_array();
      json.end_object();
    }
    json.end_array();
    json.key("vtu").value(vtu.string());
    json.key("pvd").value(pvd.string());
  }
  json.end_object();
}

int run_solve(const SolveOptions& o) {
  if (o.press.size() % 6 != 0) {
    std::cerr << "error: --press takes six numbers per probe: X Y Z FX FY FZ (m and N)\n";
    return kExitBadInput;
  }
  if (o.points.size() % 3 != 0) {
    std::cerr << "error: --point takes three numbers: X Y Z (m)\n";
    return kExitBadInput;
  }
  // Non-finite values never get here: run_cli refuses them for every option.
  for (std::size_t i = 0; i + 5 < o.press.size(); i += 6) {
    const double force = std::sqrt(o.press[i + 3] * o.press[i + 3] + o.press[i + 4] * o.press[i + 4] + o.press[i + 5] * o.press[i + 5]);
    if (force > 300) {
      std::cerr << "error: --press: a force of " << force << " N; a probe presses with at most 300 N (forces in newtons)\n";
      return kExitBadInput;
    }
  }
  std::optional<config::Scene> loaded = load_scene_or_report(o.scene);
  if (!loaded) return kExitBadInput;
  config::Scene scene = std::move(*loaded);
  try {  // before anything is built: the output must not replace the scene or its mesh
    const fs::path dir = o.out.empty() ? fs::path("fetouch-solve") / scene.name : fs::path(o.out);
    // What a solve writes there: NAME.vtu, NAME.pvd, NAME_K.vtu (time steps), NAME*.pvtu pieces, summary.json.
    const auto writes = [&scene](const std::string& file) {
      const std::string ext = fs::path(file).extension().string();
      return file == "summary.json" || (file.rfind(scene.name, 0) == 0 && (ext == ".vtu" || ext == ".pvd" || ext == ".pvtu"));
    };
    refuse_overwriting({dir}, {{o.scene, "the scene"}, {scene.mesh.path, "the scene's mesh"}}, dir, writes);
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  }
  ensure_mpi();
  std::unique_ptr<fem::TissueModel> model;
  std::vector<int> patches;
  try {
    scene.mesh = mesh_scene_volume(scene);  // a volume is meshed (once, cached) first
    log::info() << "building the tissue model of " << scene.name;
    model = fem::build_tissue_model(scene);
    const double radius = o.radius_m > 0 ? o.radius_m : scene.probes.empty() ? 5e-3 : scene.probes.front().radius_m;
    for (size_t p = 0; p < o.press.size(); p += 6) {
      const int patch = model->solver->add_contact_patch(dealii::Point<3>(o.press[p], o.press[p + 1], o.press[p + 2]), radius);
      dealii::Tensor<1, 3> force;
      for (int d = 0; d < 3; ++d) force[d] = o.press[p + 3 + d];
      model->solver->set_patch_force(patch, force);
      patches.push_back(patch);
    }
  } catch (const fem::PhysicalProblem& e) {
    std::cerr << "error: the work failed: " << o.scene << ": " << e.what() << physical_advice(scene) << "\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << "error: " << o.scene << ": " << e.what() << "\n";
    return kExitBadInput;
  }
  std::optional<fem::QuasiStaticSolver::Dynamics> dynamics;
  try {
    dynamics = fem::scene_dynamics(scene, model.get());
  } catch (const std::exception& e) {
    std::cerr << "error: " << o.scene << ": " << e.what() << "\n";
    return kExitBadInput;
  }
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const bool parallel = model->solver->ranks() > 1;
  const fs::path dir = o.out.empty() ? fs::path("fetouch-solve") / scene.name : fs::path(o.out);
  int made = 1;
  if (rank == 0) {
    std::error_code error;
    fs::create_directories(dir, error);
    made = error ? 0 : 1;
  }
  MPI_Bcast(&made, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (!made) {
    if (rank == 0) std::cerr << "error: cannot create the output folder " << dir.string() << "\n";
    return kExitFailure;
  }
  // The deformed state: one VTU (serial), or on N ranks each rank's cells and a PVTU gathering them.
  // Collective under MPI; rank 0 gets the file to list in the PVD.
  const auto write_state = [&](unsigned int counter, const std::string& serial_name) -> std::string {
    if (parallel) return fs::path(model->solver->write_vtu_pieces(dir.string(), scene.name, counter)).filename().string();
    if (rank == 0) model->solver->write_vtu((dir / serial_name).string());
    return serial_name;
  };
  fem::NewtonSettings newton = model->newton;
  newton.load_steps = o.steps;
  const auto start = std::chrono::steady_clock::now();
  fem::SolveReport report;
  std::vector<TimeStep> series;
  std::vector<std::pair<double, std::string>> frames;  // (time, VTU file name) for the PVD
  if (!dynamics) {
    log::info() << "solving: " << model->solver->dofs() << " degrees of freedom, " << model->solver->cells() << " cells, "
                << o.steps << " load steps";
    report = model->solver->solve(newton);
  } else {
    // A dynamic load case: the loads act from t = 0 (a step), time steps of 1 / solver.rate_hz.
    model->solver->enable_dynamics(*dynamics);
    newton.load_steps = 1;
    const int count = std::max(1, static_cast<int>(std::lround(o.duration_s / dynamics->time_step_s)));
    log::info() << "solving: " << model->solver->dofs() << " degrees of freedom, " << count << " time steps of "
                << dynamics->time_step_s << " s";
    Progress progress("time steps", count, std::cerr, Progress::stderr_is_terminal());
    for (int k = 1; k <= count; ++k) {
      const fem::SolveReport step = model->solver->solve(newton);
      report.total_iterations += step.total_iterations;
      report.cuts += step.cuts;
      report.steps = step.steps;
      report.converged = step.converged;
      report.failure = step.failure.empty() ? "" : "time step " + std::to_string(k) + ": " + step.failure;
      if (!step.converged) break;
      TimeStep t;
      t.t = k * dynamics->time_step_s;
      t.newton_iterations = step.total_iterations;
      t.max_displacement_m = model->solver->max_displacement();
      if (!patches.empty()) t.probe_displacement = model->solver->patch_displacement(patches.front());
      series.push_back(t);
      char name[64];
      std::snprintf(name, sizeof name, "_%04d.vtu", k);
      try {
        const std::string file = write_state(static_cast<unsigned int>(k), scene.name + name);
        if (rank == 0) frames.emplace_back(t.t, file);
      } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << "\n";
        return kExitFailure;
      }
      progress.update(k);
    }
    progress.finish();
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // In parallel the state is the PVTU that gathers the ranks' pieces (deal.II's naming).
  const fs::path vtu = dir / (scene.name + (parallel ? "_0000.pvtu" : ".vtu")), pvd = dir / (scene.name + ".pvd"), summary = dir / "summary.json";
  // The summary is computed once (it assembles to get the reactions) for the file and stdout.
  std::ostringstream json;
  const std::vector<double> peak_memory_mb = peak_resident_mb_per_rank();  // collective
  const auto shares = model->solver->shares();                             // collective
  write_json(json, o, scene, *model, report, seconds, patches, vtu, pvd, series, peak_memory_mb, shares);
  json << "\n";
  if (report.converged && frames.empty() && series.empty()) {  // a quasi-static case: its one state
    try {
      const std::string file = write_state(0, vtu.filename().string());
      if (rank == 0) frames.emplace_back(1.0, file);
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitFailure;
    }
  }
  // Under mpirun every rank solved (the same state on each); rank 0 reports.
  if (rank != 0) return report.converged ? kExitOk : kExitFailure;
  try {
    if (!frames.empty()) {  // the time series of a dynamic case, or the one state
      write_pvd(pvd, frames);
    }
    write_text_file(summary, json.str());
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitFailure;
  }
  // A failed solve is said on standard error too (under --json standard output is the report alone).
  if (!report.converged)
    std::cerr << "error: the work failed: " << o.scene << ": the solve did not converge: " << report.failure
              << physical_advice(scene) << "\n";
  if (o.json) {
    std::cout << json.str();
  } else {
    std::cout << scene.name << ": " << (report.converged ? "converged" : "FAILED") << " in " << report.total_iterations
              << " Newton iterations (" << report.cuts << " load-step cuts), " << std::setprecision(3) << seconds << " s, "
              << model->solver->dofs() << " dofs, peak memory " << std::lround(peak_memory_mb.front()) << " MB"
              << (peak_memory_mb.size() > 1 ? " on rank 0" : "") << "\n";
    if (parallel) std::cout << "  " << partition_line(shares) << "\n";
    if (!report.converged) std::cout << "  why: " << report.failure << "\n";
    else {
      std::cout << "  max displacement " << model->solver->max_displacement() * 1e3 << " mm\n";
      if (scene.effects.has(config::Effect::cavity))
        std::cout << "  cavity pressure " << model->solver->cavity_pressure() << " Pa, volume "
                  << model->solver->cavity_volume() * 1e6 << " ml (" << std::setprecision(3)
                  << 100 * (model->solver->cavity_volume() / model->solver->cavity_reference_volume() - 1) << " %)\n";
      for (size_t p = 0; p < patches.size(); ++p) {
        const auto u = model->solver->patch_displacement(patches[p]);
        std::cout << "  probe " << p + 1 << " displacement (" << u[0] * 1e3 << ", " << u[1] * 1e3 << ", " << u[2] * 1e3
                  << ") mm\n";
      }
      std::cout << "  wrote " << pvd.string() << " (open in ParaView), " << summary.string() << "\n";
    }
  }
  return report.converged ? kExitOk : kExitFailure;
}

}  // namespace

void add_solve_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<SolveOptions>();
  CLI::App* cmd = parent.add_subcommand("solve", "Solve a quasi-static load case on a scene's tissue");
  cmd->footer(
      "The scene's supports (fixed regions), tractions and gravity, plus probes pressing with given\n"
      "forces, applied in load steps with Newton's method. Writes DIR/NAME.vtu and DIR/NAME.pvd (the\n"
      "deformed tissue with displacement, J and von Mises stress; open the .pvd in ParaView and warp\n"
      "by the displacement) and DIR/summary.json. Exit code 0 when converged, 1 when not, 2 on bad input.\n"
      "Example: fetouch solve config/scenes/block_press.yaml --press 0.05 0.04 0.05 0 0 -0.3");
  cmd->add_option("scene", o->scene, "Scene file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "Output folder (default fetouch-solve/NAME)");
  cmd->add_option("--press", o->press, "A probe pressing: X Y Z FX FY FZ (surface point in m, force in N); repeatable")
      ->allow_extra_args(false)->expected(6)->take_all();
  cmd->add_option("--point", o->points, "Report the displacement at X Y Z (m); repeatable")->expected(3)->take_all();
  cmd->add_option("--radius", o->radius_m, "Probe radius in m (default: the scene's first probe)")->check(CLI::Range(1e-4, 0.05));
  cmd->add_option("--steps", o->steps, "Load steps")->check(CLI::Range(1, 1000))->capture_default_str();
  cmd->add_option("--duration", o->duration_s, "Simulated time of a scene with inertia, s (loads as a step at t = 0)")
      ->check(CLI::Range(1e-6, 1e4))->capture_default_str();
  cmd->add_flag("--json", o->json, "Print the JSON summary on stdout");
  cmd->callback([o, &exit_code]() { exit_code = run_solve(*o); });
}

}  // namespace fetouch::app

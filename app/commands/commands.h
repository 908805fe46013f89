// Each subcommand registers its options on the parent CLI11 app and sets the callback that runs it.
// The callback stores the exit code in `exit_code`.
#pragma once

namespace CLI {
class App;
}

namespace fetouch::app {

void add_check_command(CLI::App& parent, int& exit_code);
void add_stability_command(CLI::App& parent, int& exit_code);
void add_solve_command(CLI::App& parent, int& exit_code);
void add_phantom_command(CLI::App& parent, int& exit_code);
void add_reconstruct_command(CLI::App& parent, int& exit_code);
void add_mesh_command(CLI::App& parent, int& exit_code);
void add_labels_command(CLI::App& parent, int& exit_code);
void add_render_command(CLI::App& parent, int& exit_code);
void add_replay_command(CLI::App& parent, int& exit_code);
void add_trajectory_command(CLI::App& parent, int& exit_code);
void add_run_command(CLI::App& parent, int& exit_code);
void add_devices_command(CLI::App& parent, int& exit_code);
void add_trainer_command(CLI::App& parent, int& exit_code);
void add_review_command(CLI::App& parent, int& exit_code);
void add_study_command(CLI::App& parent, int& exit_code);

}  // namespace fetouch::app

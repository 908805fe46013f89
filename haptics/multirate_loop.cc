#include "haptics/multirate_loop.h"

#include <stdexcept>

namespace fetouch::haptics {

MultirateState::MultirateState(int contacts)
    : held_newest(Eigen::VectorXd::Zero(contacts)),
      held_previous(Eigen::VectorXd::Zero(contacts)),
      force_newest(Eigen::VectorXd::Zero(contacts)),
      force_previous(Eigen::VectorXd::Zero(contacts)),
      pending_surface(Eigen::VectorXd::Zero(contacts)),
      pending_force(Eigen::VectorXd::Zero(contacts)) {}

MultirateLoop::MultirateLoop(LocalModel local_model, LinearEnvironment environment, HoldKind hold,
                             int ratio)
    : local_model_(std::move(local_model)),
      environment_(std::move(environment)),
      hold_(hold),
      ratio_(ratio),
      state_(environment_.contacts()),
      held_(Eigen::VectorXd::Zero(environment_.contacts())),
      reference_(Eigen::VectorXd::Zero(environment_.contacts())) {
  if (ratio < 1) throw std::invalid_argument("MultirateLoop: the ratio N must be at least 1");
}

const Eigen::VectorXd& MultirateLoop::tick(const Eigen::VectorXd& device) noexcept {
  const int i = static_cast<int>(state_.tick % ratio_);
  if (i == 0 && state_.tick > 0) {
    state_.held_previous.swap(state_.held_newest);
    state_.held_newest = state_.pending_surface;
    state_.force_previous.swap(state_.force_newest);
    state_.force_newest = state_.pending_force;
  }
  apply_hold(hold_, i, ratio_, state_.held_newest, state_.held_previous, held_);
  apply_hold(hold_, i, ratio_, state_.force_newest, state_.force_previous, reference_);
  const Eigen::VectorXd& force = local_model_.step(device, held_, reference_);
  if (i == 0) {
    state_.pending_force = force;
    state_.pending_surface = environment_.step(force);
  }
  ++state_.tick;
  return force;
}

}  // namespace fetouch::haptics

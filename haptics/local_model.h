// The local model: renders force at every haptic tick from the device position and the surface
// held from the slow environment. All four variants share one state, so one block holds them:
//
//   penetration     e(k) = x_h(k) - x_p(k)                  (along each contact's normal)
//   P               F(k) = Kh e(k)
//   PI              F(k) = Kh e(k) + s(k),   s(k+1) = s(k) + I e(k)       i.e. L(z) = Kh + I/(z-1)
//   Smith           x_p(k) = x_held(k) + W (F(k) - F_ref(k))   (predicted surface), else x_p = x_held
//
// x_held and F_ref come from the hold (hold.h): the newest environment answer and the force that
// produced it. With the predictor, F(k) appears on both sides; the loop is solved exactly:
//   (I + Kh W) F(k) = Kh (x_h(k) - x_held(k) + W F_ref(k)) + s(k),
// with (I + Kh W)^-1 factored once per change of Kh or W, never in the tick.
//
// State-space realization per tick, state s (PI variants only), inputs (x_h, x_held, F_ref):
//   without Smith:  s+ = s + I (x_h - x_held),           F = Kh (x_h - x_held) + s
//   with Smith:     G = (I + Kh W)^-1,  F = G (Kh (x_h - x_held + W F_ref) + s),
//                   s+ = s + I (x_h - x_held - W (F - F_ref))
// Anti-windup: s is clamped to |s| <= s_max per contact, and set_integrating(false) pauses it (the
// loop does so while an environment answer is late: the frame's integration is then complete);
// set_integrating(c, false) holds one contact's against winding up (the loop does so while the
// layers after the model cut that contact's force: an integrator behind a scaled or clamped force
// only winds up); it may still unwind, so a held contact can let go.
// Unilateral contact (set_unilateral, the 3D loop's setting; the analysis keeps it off): a contact
// whose force comes out F <= 0 is not touching: F = 0 and s = 0 (reset on contact loss). Since F
// passes through 0 continuously as the device leaves, neither onset nor release steps the force.
// Real-time safe after construction: step(), set_gains() and set_compliance() of the constructed
// size allocate nothing ((I + Kh W) is factored in place by a preallocated LU).
#pragma once

#include <Eigen/Dense>

#include <string>

namespace fetouch::haptics {

enum class LocalModelKind { p, pi, smith, pi_smith };

constexpr bool has_integrator(LocalModelKind kind) {
  return kind == LocalModelKind::pi || kind == LocalModelKind::pi_smith;
}
constexpr bool has_predictor(LocalModelKind kind) {
  return kind == LocalModelKind::smith || kind == LocalModelKind::pi_smith;
}

// The names scenes and command lines use: "p", "pi", "smith", "pi_smith".
const char* to_string(LocalModelKind kind);
// False (and `kind` untouched) for any other name.
bool parse_local_model(const std::string& name, LocalModelKind& kind);

struct LocalModelGains {
  double proportional = 0;  // Kh
  double integral = 0;      // I, per tick
};

class LocalModel {
 public:
  LocalModel(LocalModelKind kind, int contacts);

  LocalModelKind kind() const { return kind_; }
  bool has_integrator() const { return haptics::has_integrator(kind_); }
  bool has_predictor() const { return haptics::has_predictor(kind_); }

  // Another variant of the same size (real-time safe): an integrator it gains starts from zero.
  void set_kind(LocalModelKind kind) noexcept;
  void set_gains(const LocalModelGains& gains);
  void set_compliance(const Eigen::MatrixXd& compliance);  // W, for the Smith variants
  void set_integrator_limit(double limit) { integrator_limit_ = limit; }
  void set_unilateral(bool unilateral) { unilateral_ = unilateral; }
  void set_integrating(bool integrating) { integrating_ = integrating; }
  // Per contact (anti-windup): a contact whose force the layers after the model cut (the passivity
  // layer's scale, the safety clamp) winds its integrator no further until its force passes again.
  void set_integrating(Eigen::Index contact, bool integrating) noexcept { integrating_mask_(contact) = integrating ? 1.0 : 0.0; }
  const LocalModelGains& gains() const { return gains_; }

  // One tick: returns F(k) and advances s.
  const Eigen::VectorXd& step(const Eigen::VectorXd& device, const Eigen::VectorXd& held_surface,
                              const Eigen::VectorXd& reference_force) noexcept;

  const Eigen::VectorXd& integrator() const { return integrator_; }
  // The penetration behind the predicted surface at the last step (e(k) - (W (F - F_ref))(k) with
  // the predictor, e(k) without): where the proxy sits.
  const Eigen::VectorXd& predicted_penetration() const { return error_; }
  void set_integrator(const Eigen::VectorXd& s) { integrator_ = s; }
  void reset() { integrator_.setZero(); }

 private:
  void refactor();

  LocalModelKind kind_;
  LocalModelGains gains_;
  double integrator_limit_ = 1e300;
  bool unilateral_ = false;
  bool integrating_ = true;
  Eigen::MatrixXd compliance_;       // W
  Eigen::MatrixXd loop_matrix_;      // I + Kh W
  Eigen::PartialPivLU<Eigen::MatrixXd> loop_lu_;
  Eigen::VectorXd integrator_, force_, error_, rhs_;
  Eigen::VectorXd integrating_mask_;  // 1: the contact integrates, 0: it holds
};

}  // namespace fetouch::haptics

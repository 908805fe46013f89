// What is physically plausible, with its unit, for the numbers a scene gives: soft tissue, a probe,
// a haptic device, a solver. A value outside is refused with the range and the reason (issue 17:
// a 1e300 m box or a 10 m probe radius is a typo, not a scene). README.md lists them.
#pragma once

#include "config/yaml_reader.h"

namespace fetouch::config::plausible {

using detail::Range;

// Geometry.
inline const Range tissue_length_m{1e-4, 2, false, false, "0.1 mm to 2 m: a biopsy to a whole torso"};
inline const Range probe_radius_m{1e-4, 0.05, false, false, "0.1 mm to 5 cm: a needle to an ultrasound probe"};
inline const Range element_size_m{1e-4, 0.5, false, false, "0.1 mm to 50 cm"};
inline const Range smoothing_sigma_m{0, 0.05, true, false, "up to 5 cm"};
inline const Range plane_tolerance_m{0, 0.1, true, false, "up to 10 cm"};
// Tissue.
inline const Range modulus_pa{1, 1e9, false, false, "1 Pa to 1 GPa: the softest gel to tendon"};
inline const Range hyperelastic_constant_pa{0.1, 1e9, false, false, "0.1 Pa to 1 GPa"};
inline const Range bulk_modulus_pa{1, 1e10, false, false, "1 Pa to 10 GPa: water is 2.2 GPa"};
inline const Range density_kg_per_m3{100, 3000, false, false, "100 to 3000 kg/m^3: lung to bone; soft tissue is about 1050"};
inline const Range pressure_pa{0, 1e6, false, false, "0 to 1 MPa"};
inline const Range traction_pa{-1e6, 1e6, false, false, "up to 1 MPa"};
// Haptic device and loop.
inline const Range haptic_rate_hz{100, 20000, false, false, "100 Hz to 20 kHz; haptic devices run at about 1 kHz"};
inline const Range solver_rate_hz{0.1, 1000, false, false, "a frame every 10 s to 1000 frames a second"};
inline const Range max_force_n{0, 300, true, false, "up to 300 N: a desktop device gives 3 to 20 N, the strongest about 250 N"};
inline const Range max_force_rate_n_per_s{0, 1e6, true, false, "up to 10^6 N/s"};
inline const Range watchdog_timeout_s{0, 10, true, false, "up to 10 s"};
inline const Range gain_n_per_m{0, 1e6, true, false, "up to 10^6 N/m: stiffer than any device renders"};
inline const Range hand_mass_kg{0, 10, true, false, "up to 10 kg"};
inline const Range hand_stiffness_n_per_m{0, 1e5, true, false, "up to 10^5 N/m"};
inline const Range workspace_scale{0, 100, true, false, "up to 100 scene metres per device metre"};
inline const Range workspace_offset_m{-10, 10, false, false, "within 10 m of the scene's origin"};
inline const Range device_button{0, 31, false, false, "a button number from 0 to 31"};
inline const Range hand_damping_n_s_per_m{0, 1e3, false, false, "up to 1000 N s/m"};
// Accuracy.
inline const Range accuracy_position_m{0, 0.01, true, false, "up to 1 cm"};
inline const Range accuracy_force_n{0, 10, true, false, "up to 10 N"};
inline const Range newton_absolute_tolerance{0, 1e3, true, false, "up to 1000 (residual units, N)"};
// Probes in a scene: more than any trainer has hands for.
constexpr int kMaxProbes = 16;

}  // namespace fetouch::config::plausible

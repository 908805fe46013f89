// A synthetic fetal ultrasound phantom: a procedurally generated fetus-like body (head with a bright
// skull, trunk, four limbs) floating in amniotic fluid inside a uterine wall, inside soft tissue, with
// its ground-truth label map, and rendered with the look of a 3D ultrasound volume:
//   - echogenicity per tissue (fluid anechoic, wall and skull bright, fetus mid-grey);
//   - multiplicative speckle: the magnitude of a complex Gaussian field smoothed over a speckle size
//     (fully developed speckle: Rayleigh distributed, std/mean = sqrt(4/pi - 1) = 0.523);
//   - depth attenuation along the beam (the probe sits above the volume, beams go down -z):
//     exp(-mu depth);
//   - shadowing: each interface a beam crosses reflects part of its energy (the skull most), so the
//     region below a bright boundary is darker.
// Everything follows from the seed: the same seed gives the same bytes.
//
// Units: millimetres (an image); the volume is centred on the origin. The uterus frame: x towards the
// fundus (the mother's head), z anterior (the beams come down from +z), y = z × x (the mother's
// right).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "imaging/fetal_biometry.h"

namespace fetouch::imaging {

// A scalar volume: x fastest, then y, then z.
template <class T>
struct Volume {
  std::array<int, 3> dimensions{0, 0, 0};
  std::array<double, 3> spacing_mm{1, 1, 1};
  std::array<double, 3> origin_mm{0, 0, 0};  // centre of voxel (0, 0, 0)
  // Direction cosines, row-major: column c is the direction of index axis c in space.
  std::array<double, 9> direction{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::vector<T> data;
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(k) * dimensions[1] + j) * dimensions[0] + i;
  }
  // origin + direction (i, j, k) x spacing
  std::array<double, 3> position_mm(int i, int j, int k) const {
    const double step[3] = {i * spacing_mm[0], j * spacing_mm[1], k * spacing_mm[2]};
    std::array<double, 3> p = origin_mm;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) p[r] += direction[3 * r + c] * step[c];
    return p;
  }
  double voxel_volume_mm3() const { return spacing_mm[0] * spacing_mm[1] * spacing_mm[2]; }
};

enum PhantomLabel : std::uint8_t {
  kTissue = 0,  // outside the uterus
  kUterineWall = 1,
  kAmnioticFluid = 2,
  kHead = 3,
  kSkull = 4,
  kTrunk = 5,
  kLimb = 6,
};
inline bool is_fetus(std::uint8_t label) { return label >= kHead; }

struct PhantomSettings {
  std::uint32_t seed = 1;
  double spacing_mm = 1.0;
  std::array<double, 3> size_mm{160, 130, 120};
  bool speckle = true;
  double speckle_size_mm = 1.2;       // correlation length of the speckle
  double attenuation_per_mm = 0.006;  // mu, amplitude
  bool shadowing = true;
  // The whole fetus moved by this much from where the seed puts it (a fetus lying against the
  // front wall: {0, 0, 20}). Where it then reaches the wall the wall wins: the fetus is cut off.
  std::array<double, 3> fetus_offset_mm{0, 0, 0};
  // The fetus turned so that its head and back face these directions (unit, square to each other;
  // config/fetal_pose.h names them as obstetrics does) and centred in the sac along its axis,
  // within 0.1 rad about z of the request (the seed's turn). None: the seed's fetus, head towards
  // +x turned by up to 0.35 rad about z, back towards +z, exactly as before poses existed.
  struct Orientation {
    std::array<double, 3> head{-1, 0, 0}, back{0, 0, 1};
  };
  std::optional<Orientation> fetus_orientation;
  // The fetus grown to this age (weeks, 14 to 42) by Hadlock's biometry (imaging/fetal_biometry.h),
  // the uterus and the volume (size_mm) with it. None: the seed's fetus, about 16 weeks, as always.
  std::optional<double> gestational_age_weeks;
};

// The shapes, after the seed's random variation: ellipsoids (centre, semi-axes, rotation about z)
// and limbs (capsules between two points).
struct PhantomGeometry {
  struct Ellipsoid {
    std::array<double, 3> centre{0, 0, 0}, radii{1, 1, 1};
    double yaw = 0;  // rotation about z, rad
    // When set, the rotation instead (row-major; column c: the ellipsoid's axis c in space).
    std::optional<std::array<double, 9>> axes;
  };
  struct Capsule {
    std::array<double, 3> a{0, 0, 0}, b{0, 0, 0};
    double radius = 1;
  };
  Ellipsoid uterus_outer, uterus_inner, head, trunk;
  double skull_thickness_mm = 3;
  std::array<Capsule, 4> limbs;
  // The label at a point, mm.
  std::uint8_t label_at(const std::array<double, 3>& x) const;
};

struct Phantom {
  PhantomGeometry geometry;
  Volume<std::uint8_t> labels;
  Volume<std::uint8_t> image;  // 0..255
};

// Throws std::invalid_argument for an orientation whose directions are not unit and square.
PhantomGeometry phantom_geometry(std::uint32_t seed, const std::array<double, 3>& fetus_offset_mm = {0, 0, 0},
                                 const std::optional<PhantomSettings::Orientation>& orientation = std::nullopt,
                                 const FetalGrowth& growth = {});
// The shapes make_phantom(settings) draws: its seed, offset and orientation, grown to its gestational
// age (growth_at) when it has one. Throws as above.
PhantomGeometry phantom_geometry(const PhantomSettings& settings);
// Throws std::invalid_argument for a spacing or size that is not positive, or a volume over 2^31 voxels.
Phantom make_phantom(const PhantomSettings& settings);

}  // namespace fetouch::imaging

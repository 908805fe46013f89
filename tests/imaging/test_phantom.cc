// The synthetic fetal phantom against what it is built from: the label volumes against the
// ellipsoids' closed-form volumes, fully developed speckle's Rayleigh statistics (std/mean = 0.523),
// depth attenuation exp(-mu depth), a shadow below the skull, reproducibility from the seed, and a
// MetaImage round trip through VTK with spacing and origin kept; and a fetus in every pose measured
// on its label map.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include "config/fetal_pose.h"
#include "imaging/phantom.h"
#include "imaging/volume_io.h"

namespace fetouch::imaging {
namespace {

double ellipsoid_volume(const PhantomGeometry::Ellipsoid& e) { return 4.0 / 3 * M_PI * e.radii[0] * e.radii[1] * e.radii[2]; }

std::map<int, double> label_volumes(const Phantom& p) {
  std::map<int, double> v;
  for (const auto label : p.labels.data) v[label] += p.labels.voxel_volume_mm3();
  return v;
}

TEST(Phantom, LabelVolumesMatchTheEllipsoids) {
  PhantomSettings s;
  s.speckle = false;
  const Phantom p = make_phantom(s);
  auto v = label_volumes(p);
  const double inner = ellipsoid_volume(p.geometry.uterus_inner), outer = ellipsoid_volume(p.geometry.uterus_outer);
  double sac = 0, fetus = 0;
  for (const auto& [label, volume] : v) {
    if (label >= kAmnioticFluid) sac += volume;
    if (is_fetus(static_cast<std::uint8_t>(label))) fetus += volume;
  }
  std::printf("sac %.0f mm^3 (ellipsoid %.0f), wall %.0f mm^3 (shell %.0f), fetus %.0f mm^3, fluid %.0f mm^3\n", sac, inner,
              v[kUterineWall], outer - inner, fetus, v[kAmnioticFluid]);
  EXPECT_NEAR(sac, inner, 0.01 * inner);
  EXPECT_NEAR(v[kUterineWall], outer - inner, 0.03 * (outer - inner));
  // The fetus: at most the sum of its parts, at least its largest part, and afloat (fluid around).
  const double head = ellipsoid_volume(p.geometry.head), trunk = ellipsoid_volume(p.geometry.trunk);
  EXPECT_GT(fetus, std::max(head, trunk));
  EXPECT_GT(v[kAmnioticFluid], 0.3 * sac);
  EXPECT_GT(v[kSkull], 0.0);
  EXPECT_GT(v[kLimb], 0.0);
}

TEST(Phantom, SameSeedSameBytesOtherSeedOtherFetus) {
  PhantomSettings s;
  s.spacing_mm = 2;
  const Phantom a = make_phantom(s), b = make_phantom(s);
  EXPECT_EQ(a.image.data, b.image.data);
  EXPECT_EQ(a.labels.data, b.labels.data);
  s.seed = 2;
  EXPECT_NE(make_phantom(s).labels.data, a.labels.data);
}

// Moving the fetus: its labels' centroid moves by the offset (to a voxel), the wall's labels are
// unchanged, and its volume is kept while it stays clear of the wall.
TEST(Phantom, TheFetusOffsetMovesTheFetusAndNothingElse) {
  const auto centroid_and_volume = [](const Phantom& p) {
    std::array<double, 4> c{0, 0, 0, 0};
    const auto& l = p.labels;
    for (int k = 0; k < l.dimensions[2]; ++k)
      for (int j = 0; j < l.dimensions[1]; ++j)
        for (int i = 0; i < l.dimensions[0]; ++i)
          if (is_fetus(l.data[l.index(i, j, k)])) {
            const auto x = l.position_mm(i, j, k);
            for (int d = 0; d < 3; ++d) c[d] += x[d];
            c[3] += 1;
          }
    for (int d = 0; d < 3; ++d) c[d] /= c[3];
    c[3] *= l.voxel_volume_mm3();
    return c;
  };
  PhantomSettings s;
  s.speckle = false;
  const Phantom home = make_phantom(s);
  s.fetus_offset_mm = {4, -3, 12};
  const Phantom moved = make_phantom(s);
  const auto a = centroid_and_volume(home), b = centroid_and_volume(moved);
  std::printf("fetus centroid (%.2f, %.2f, %.2f) mm -> (%.2f, %.2f, %.2f) mm, volume %.0f -> %.0f mm^3\n", a[0], a[1], a[2],
              b[0], b[1], b[2], a[3], b[3]);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(b[d] - a[d], s.fetus_offset_mm[d], 0.5);
  EXPECT_NEAR(b[3], a[3], 0.01 * a[3]);
  std::size_t wall_changed = 0;
  for (std::size_t v = 0; v < home.labels.data.size(); ++v)
    wall_changed += (home.labels.data[v] == kUterineWall) != (moved.labels.data[v] == kUterineWall);
  EXPECT_EQ(wall_changed, 0u);
}

TEST(Phantom, SpeckleIsRayleighAndDepthAttenuates) {
  PhantomSettings s;
  s.shadowing = false;
  const Phantom p = make_phantom(s);
  // Tissue outside the uterus, by depth (voxel layers from the top): mean and spread.
  const int nz = p.image.dimensions[2];
  std::vector<double> sum(nz, 0), sum2(nz, 0), count(nz, 0);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < p.image.dimensions[1]; ++j)
      for (int i = 0; i < p.image.dimensions[0]; ++i) {
        const std::size_t v = p.image.index(i, j, k);
        if (p.labels.data[v] != kTissue) continue;
        sum[k] += p.image.data[v], sum2[k] += double(p.image.data[v]) * p.image.data[v], count[k] += 1;
      }
  // Speckle: std/mean within a layer (one depth: one attenuation).
  double ratio = 0;
  int layers = 0;
  for (int k = 5; k < nz - 5; k += 10) {
    const double mean = sum[k] / count[k], var = sum2[k] / count[k] - mean * mean;
    ratio += std::sqrt(var) / mean, ++layers;
  }
  ratio /= layers;
  std::printf("speckle std/mean %.4f (Rayleigh %.4f)\n", ratio, std::sqrt(4 / M_PI - 1));
  EXPECT_NEAR(ratio, std::sqrt(4 / M_PI - 1), 0.02);
  // Attenuation: the layer means fall as exp(-mu depth).
  const int top = nz - 6, bottom = 5;
  const double measured = (sum[bottom] / count[bottom]) / (sum[top] / count[top]);
  const double expected = std::exp(-s.attenuation_per_mm * (top - bottom) * s.spacing_mm);
  std::printf("attenuation over %d mm: %.4f (exp(-mu d) %.4f)\n", top - bottom, measured, expected);
  EXPECT_NEAR(measured, expected, 0.04 * expected);
}

TEST(Phantom, TheSkullCastsAShadow) {
  PhantomSettings s;
  s.speckle = false;
  s.attenuation_per_mm = 0;
  const Phantom shadowed = make_phantom(s);
  s.shadowing = false;
  const Phantom clear = make_phantom(s);
  // The column through the head's centre, below the head: darker than without shadowing.
  const auto& head = shadowed.geometry.head;
  const auto& img = shadowed.image;
  const int i = static_cast<int>(std::lround((head.centre[0] - img.origin_mm[0]) / img.spacing_mm[0]));
  const int j = static_cast<int>(std::lround((head.centre[1] - img.origin_mm[1]) / img.spacing_mm[1]));
  double below_shadowed = 0, below_clear = 0;
  for (int k = 0; k < img.dimensions[2]; ++k) {
    const auto x = img.position_mm(i, j, k);
    if (x[2] > head.centre[2] - head.radii[2] - 2) continue;  // under the head only
    below_shadowed += shadowed.image.data[img.index(i, j, k)];
    below_clear += clear.image.data[img.index(i, j, k)];
  }
  std::printf("below the head: %.0f shadowed against %.0f without shadowing\n", below_shadowed, below_clear);
  EXPECT_LT(below_shadowed, 0.5 * below_clear);  // two skull interfaces take 1 - 0.55^2 = 70 %
}

TEST(Phantom, MetaImageRoundTripKeepsVoxelsSpacingAndOrigin) {
  PhantomSettings s;
  s.spacing_mm = 2;
  const Phantom p = make_phantom(s);
  const auto path = std::filesystem::temp_directory_path() / ("phantom_" + std::to_string(::getpid()) + ".mha");
  write_volume(p.image, path);
  const Volume<float> back = read_volume(path);
  std::filesystem::remove(path);
  EXPECT_EQ(back.dimensions, p.image.dimensions);
  for (int d = 0; d < 3; ++d) {
    EXPECT_DOUBLE_EQ(back.spacing_mm[d], p.image.spacing_mm[d]);
    EXPECT_NEAR(back.origin_mm[d], p.image.origin_mm[d], 1e-9);
  }
  ASSERT_EQ(back.data.size(), p.image.data.size());
  for (std::size_t v = 0; v < back.data.size(); ++v) ASSERT_EQ(back.data[v], p.image.data[v]) << "voxel " << v;
}

TEST(Phantom, BadSettingsAndFilesAreRefused) {
  PhantomSettings s;
  s.spacing_mm = 0;
  EXPECT_THROW(make_phantom(s), std::invalid_argument);
  s.spacing_mm = 0.01;  // 16000 x 13000 x 12000 voxels
  EXPECT_THROW(make_phantom(s), std::invalid_argument);
  EXPECT_THROW(read_volume("/nonexistent/volume.mha"), std::runtime_error);
  const auto path = std::filesystem::temp_directory_path() / ("short_" + std::to_string(::getpid()) + ".mha");
  {
    std::ofstream f(path);
    f << "ObjectType = Image\nNDims = 3\nDimSize = 10 10 10\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n"
      << std::string(100, 'x');  // 100 of 1000 voxels
  }
  try {
    read_volume(path);
    ADD_FAILURE() << "a truncated volume was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

// Every pose config/fetal_pose.h allows, measured on the label map alone: the head's centroid lies
// from the trunk's along the head direction asked, the limbs' centroid lies from the trunk's
// (square to the fetus's axis) against the back asked (the limbs are in front), and the fetus is not
// cut off by the wall (its volume within 5 % of the same seed's fetus lying along the sac).
TEST(Phantom, EveryPosePutsTheHeadBackAndLimbsWhereAsked) {
  using Vec = std::array<double, 3>;
  const auto unit = [](Vec v) {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return Vec{v[0] / n, v[1] / n, v[2] / n};
  };
  const auto dot = [](const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  for (std::uint32_t seed : {1u, 5u}) {
    double reference_volume = 0, worst_head = 1, worst_back = 1, worst_volume = 0;
    int measured = 0;
    for (const config::FetalPose& pose : config::every_pose()) {
      const config::FetalAxes axes = config::fetal_axes(pose);
      PhantomSettings s;
      s.seed = seed, s.spacing_mm = 2, s.speckle = false, s.shadowing = false;
      s.fetus_orientation = PhantomSettings::Orientation{axes.head, axes.back};
      const Phantom p = make_phantom(s);
      std::map<int, Vec> sum;
      std::map<int, double> count;
      for (int k = 0; k < p.labels.dimensions[2]; ++k)
        for (int j = 0; j < p.labels.dimensions[1]; ++j)
          for (int i = 0; i < p.labels.dimensions[0]; ++i) {
            int label = p.labels.data[p.labels.index(i, j, k)];
            if (!is_fetus(static_cast<std::uint8_t>(label))) continue;
            if (label == kSkull) label = kHead;
            const auto x = p.labels.position_mm(i, j, k);
            for (int d = 0; d < 3; ++d) sum[label][d] += x[d];
            count[label] += 1;
          }
      ASSERT_GT(count[kHead] * count[kTrunk] * count[kLimb], 0) << config::describe(pose);
      Vec head, trunk, limbs;
      for (int d = 0; d < 3; ++d)
        head[d] = sum[kHead][d] / count[kHead], trunk[d] = sum[kTrunk][d] / count[kTrunk], limbs[d] = sum[kLimb][d] / count[kLimb];
      const Vec along = unit({head[0] - trunk[0], head[1] - trunk[1], head[2] - trunk[2]});
      EXPECT_GT(dot(along, axes.head), std::cos(15 * M_PI / 180)) << config::describe(pose) << ", seed " << seed;
      worst_head = std::min(worst_head, dot(along, axes.head));
      Vec front{limbs[0] - trunk[0], limbs[1] - trunk[1], limbs[2] - trunk[2]};
      const double share = dot(front, axes.head);
      for (int d = 0; d < 3; ++d) front[d] -= share * axes.head[d];
      EXPECT_LT(dot(unit(front), axes.back), -std::cos(30 * M_PI / 180)) << config::describe(pose) << ", seed " << seed;
      worst_back = std::min(worst_back, -dot(unit(front), axes.back));
      const double volume = count[kHead] + count[kTrunk] + count[kLimb];
      if (measured++ == 0) reference_volume = volume;  // the first pose: longitudinal, cephalic, along the sac
      EXPECT_NEAR(volume, reference_volume, 0.05 * reference_volume) << config::describe(pose) << ", seed " << seed;
      worst_volume = std::max(worst_volume, std::abs(volume / reference_volume - 1));
    }
    EXPECT_EQ(measured, 48);
    std::printf("seed %u: head direction within %.1f deg, back within %.1f deg, fetal volume within %.2f %% over %d poses\n", seed,
                std::acos(worst_head) * 180 / M_PI, std::acos(worst_back) * 180 / M_PI, 100 * worst_volume, measured);
  }
}

// A fetus grown to an age, measured on its label map against Hadlock's biometry (the published
// regressions, not the phantom's own radii): the biparietal diameter (the head's width across the
// fetus) within the seed's 6 % jitter and a voxel, the trunk's girth (the ellipse through its widths
// across and front to back, Ramanujan's perimeter) within its 8 % and a voxel, and head and trunk
// inside the grown sac (the ends of their axes are fluid or fetus, not wall).
TEST(Phantom, GrowsWithGestationalAgeAsHadlockSays) {
  const config::FetalAxes axes = config::fetal_axes(*config::requested_pose("longitudinal", "cephalic", "anterior", "", 1));
  for (double weeks : {16.0, 20.0, 28.0, 36.0}) {
    PhantomSettings s;
    s.spacing_mm = 2, s.speckle = false, s.shadowing = false;
    s.fetus_orientation = PhantomSettings::Orientation{axes.head, axes.back};
    s.gestational_age_weeks = weeks;
    const Phantom p = make_phantom(s);
    // The fetus's left-right axis is y here (head -x, back +z); front to back is z.
    double head_low = 1e9, head_high = -1e9, trunk_y[2] = {1e9, -1e9}, trunk_z[2] = {1e9, -1e9};
    for (int k = 0; k < p.labels.dimensions[2]; ++k)
      for (int j = 0; j < p.labels.dimensions[1]; ++j)
        for (int i = 0; i < p.labels.dimensions[0]; ++i) {
          const int label = p.labels.data[p.labels.index(i, j, k)];
          const auto x = p.labels.position_mm(i, j, k);
          if (label == kHead || label == kSkull) head_low = std::min(head_low, x[1]), head_high = std::max(head_high, x[1]);
          if (label == kTrunk) {
            trunk_y[0] = std::min(trunk_y[0], x[1]), trunk_y[1] = std::max(trunk_y[1], x[1]);
            trunk_z[0] = std::min(trunk_z[0], x[2]), trunk_z[1] = std::max(trunk_z[1], x[2]);
          }
        }
    const double h = s.spacing_mm;
    const double bpd = head_high - head_low + h, bpd_hadlock = biparietal_diameter_mm(weeks);
    EXPECT_NEAR(bpd, bpd_hadlock, 0.06 * bpd_hadlock + h) << weeks << " weeks";
    const double a = 0.5 * (trunk_y[1] - trunk_y[0] + h), b = 0.5 * (trunk_z[1] - trunk_z[0] + h);
    const double girth = M_PI * (3 * (a + b) - std::sqrt((3 * a + b) * (a + 3 * b))), ac = abdominal_circumference_mm(weeks);
    EXPECT_NEAR(girth, ac, 0.08 * ac + 2 * M_PI * h) << weeks << " weeks";
    for (const PhantomGeometry::Ellipsoid* e : {&p.geometry.head, &p.geometry.trunk})
      for (int axis = 0; axis < 3; ++axis)
        for (double sign : {-1.0, 1.0}) {
          std::array<double, 3> end = e->centre;
          for (int d = 0; d < 3; ++d) end[d] += sign * 0.98 * e->radii[axis] * (*e->axes)[3 * d + axis];
          EXPECT_GE(p.geometry.label_at(end), kAmnioticFluid) << weeks << " weeks: the sac cuts the fetus";
        }
    std::printf("%.0f weeks: BPD %.1f mm (Hadlock %.1f), trunk girth %.0f mm (AC %.0f), volume %d x %d x %d\n", weeks, bpd,
                bpd_hadlock, girth, ac, p.labels.dimensions[0], p.labels.dimensions[1], p.labels.dimensions[2]);
  }
  PhantomSettings early;
  early.gestational_age_weeks = 12;
  EXPECT_THROW(make_phantom(early), std::invalid_argument);
}

}  // namespace
}  // namespace fetouch::imaging

#include "imaging/phantom.h"

#include "imaging/separable_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace fetouch::imaging {

namespace {

using Vec = std::array<double, 3>;

// Uniform in [lo, hi) from the raw 32-bit output, the same on every standard library (the
// <random> distributions are implementation-defined).
class Dice {
 public:
  explicit Dice(std::uint32_t seed) : engine_(seed) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * (engine_() / 4294967296.0); }
  // Standard normal by Box-Muller.
  double normal() {
    const double u1 = (engine_() + 1.0) / 4294967297.0, u2 = engine_() / 4294967296.0;
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
  }

 private:
  std::mt19937 engine_;
};

Vec rotate_z(const Vec& x, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * x[0] - s * x[1], s * x[0] + c * x[1], x[2]};
}

Vec add(const Vec& a, const Vec& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }

// R^T x for a row-major rotation R.
Vec transpose_times(const std::array<double, 9>& r, const Vec& x) {
  return {r[0] * x[0] + r[3] * x[1] + r[6] * x[2], r[1] * x[0] + r[4] * x[1] + r[7] * x[2],
          r[2] * x[0] + r[5] * x[1] + r[8] * x[2]};
}

Vec times(const std::array<double, 9>& r, const Vec& x) {
  return {r[0] * x[0] + r[1] * x[1] + r[2] * x[2], r[3] * x[0] + r[4] * x[1] + r[5] * x[2],
          r[6] * x[0] + r[7] * x[1] + r[8] * x[2]};
}

bool inside(const PhantomGeometry::Ellipsoid& e, const Vec& x, double shrink = 0) {
  const Vec offset{x[0] - e.centre[0], x[1] - e.centre[1], x[2] - e.centre[2]};
  const Vec local = e.axes ? transpose_times(*e.axes, offset) : rotate_z(offset, -e.yaw);
  double sum = 0;
  for (int d = 0; d < 3; ++d) {
    const double r = e.radii[d] - shrink;
    if (r <= 0) return false;
    sum += local[d] * local[d] / (r * r);
  }
  return sum <= 1;
}

bool inside(const PhantomGeometry::Capsule& c, const Vec& x) {
  Vec ab{c.b[0] - c.a[0], c.b[1] - c.a[1], c.b[2] - c.a[2]}, ax{x[0] - c.a[0], x[1] - c.a[1], x[2] - c.a[2]};
  const double length2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
  const double t = std::clamp((ax[0] * ab[0] + ax[1] * ab[1] + ax[2] * ab[2]) / length2, 0.0, 1.0);
  double d2 = 0;
  for (int d = 0; d < 3; ++d) d2 += (ax[d] - t * ab[d]) * (ax[d] - t * ab[d]);
  return d2 <= c.radius * c.radius;
}

// Echogenicity (mean grey level before attenuation) of each label.
double echogenicity(std::uint8_t label) {
  switch (label) {
    case kTissue: return 90;
    case kUterineWall: return 150;
    case kAmnioticFluid: return 8;
    case kHead: return 70;
    case kSkull: return 230;
    case kTrunk: return 110;
    case kLimb: return 120;
  }
  return 0;
}

// The share of a beam's energy an interface reflects back (and so takes from what lies below).
double reflectance(std::uint8_t above, std::uint8_t below) {
  if (above == below) return 0;
  if (above == kSkull || below == kSkull) return 0.45;
  if (above == kAmnioticFluid || below == kAmnioticFluid) return 0.08;
  return 0.03;
}

FetalGrowth settings_growth(const PhantomSettings& s) {
  return s.gestational_age_weeks ? growth_at(*s.gestational_age_weeks) : FetalGrowth{};
}

}  // namespace

std::uint8_t PhantomGeometry::label_at(const std::array<double, 3>& x) const {
  if (!inside(uterus_outer, x)) return kTissue;
  if (!inside(uterus_inner, x)) return kUterineWall;
  if (inside(head, x)) return inside(head, x, skull_thickness_mm) ? kHead : kSkull;
  for (const Capsule& limb : limbs)
    if (inside(limb, x)) return kLimb;
  if (inside(trunk, x)) return kTrunk;
  return kAmnioticFluid;
}

PhantomGeometry phantom_geometry(std::uint32_t seed, const std::array<double, 3>& fetus_offset_mm,
                                 const std::optional<PhantomSettings::Orientation>& orientation, const FetalGrowth& growth) {
  Dice dice(seed);
  const auto jitter = [&](double value, double relative) { return value * dice.uniform(1 - relative, 1 + relative); };
  PhantomGeometry g;
  // Grown with the fetus (every factor 1 without an age: the same numbers as always).
  const FetalGrowth& k = growth;
  g.uterus_outer.radii = {k.uterus * jitter(72, 0.05), k.uterus * jitter(56, 0.05), k.uterus * jitter(50, 0.05)};
  g.uterus_outer.yaw = dice.uniform(-0.1, 0.1);
  const double wall = jitter(7, 0.1);
  g.uterus_inner = g.uterus_outer;
  for (double& r : g.uterus_inner.radii) r -= wall;
  // The fetus in its own frame: x head-wards, z towards its back (the limbs reach forward, -z).
  const double yaw = dice.uniform(-0.35, 0.35);
  Vec centre{k.uterus * dice.uniform(-6, 2), k.uterus * dice.uniform(-4, 4), k.uterus * dice.uniform(-6, 0)};
  for (int d = 0; d < 3; ++d) centre[d] += fetus_offset_mm[d];
  PhantomGeometry::Ellipsoid trunk, head;
  trunk.radii = {k.trunk_length * jitter(27, 0.08), k.trunk_girth * jitter(15, 0.08), k.trunk_girth * jitter(14, 0.08)};
  trunk.centre = {-10 * k.trunk_length, 0, 0};
  head.radii = {k.head * jitter(18, 0.06), k.head * jitter(16, 0.06), k.head * jitter(17, 0.06)};
  head.centre = {-10 * k.trunk_length + trunk.radii[0] + head.radii[0] - 5 * k.head, 0, 3 * k.head};
  g.skull_thickness_mm = jitter(3, 0.1);
  // Arms from the shoulders forward and down, legs from the hips folded forward.
  const double r = k.limbs * jitter(4.5, 0.1), l = k.limbs;
  const Vec shoulders{-10 * k.trunk_length + 0.6 * trunk.radii[0], 0, 0}, hips{-10 * k.trunk_length - 0.7 * trunk.radii[0], 0, 0};
  const double side = trunk.radii[1] * 0.7;
  std::array<PhantomGeometry::Capsule, 4> limbs;
  limbs[0] = {{shoulders[0], side, 0}, {shoulders[0] + l * dice.uniform(2, 10), side + 6 * l, l * dice.uniform(-20, -14)}, r};
  limbs[1] = {{shoulders[0], -side, 0}, {shoulders[0] + l * dice.uniform(2, 10), -side - 6 * l, l * dice.uniform(-20, -14)}, r};
  limbs[2] = {{hips[0], side, 0}, {hips[0] + l * dice.uniform(8, 16), side + 5 * l, l * dice.uniform(-22, -16)}, 1.2 * r};
  limbs[3] = {{hips[0], -side, 0}, {hips[0] + l * dice.uniform(8, 16), -side - 5 * l, l * dice.uniform(-22, -16)}, 1.2 * r};

  // Placed in the sac: by the seed alone, turned about z; or as asked, centred along its axis.
  std::optional<std::array<double, 9>> axes;
  Vec shift{0, 0, 0};
  if (orientation) {
    const Vec& a = orientation->head;
    const Vec& b = orientation->back;
    const double aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2], bb = b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
    const double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    if (!(std::abs(aa - 1) < 1e-6 && std::abs(bb - 1) < 1e-6 && std::abs(ab) < 1e-6))
      throw std::invalid_argument("phantom: the fetus's head and back directions must be unit and square to each other");
    const Vec c{b[1] * a[2] - b[2] * a[1], b[2] * a[0] - b[0] * a[2], b[0] * a[1] - b[1] * a[0]};  // back x head
    const std::array<double, 9> pose{a[0], c[0], b[0], a[1], c[1], b[1], a[2], c[2], b[2]};
    // The seed's turn about z, scaled from the unposed fetus's 0.35 rad to 0.1: the pose stays what was asked.
    const double turn = yaw * (0.1 / 0.35), ct = std::cos(turn), st = std::sin(turn);
    axes = std::array<double, 9>{};
    for (int col = 0; col < 3; ++col) {
      (*axes)[col] = ct * pose[col] - st * pose[3 + col];
      (*axes)[3 + col] = st * pose[col] + ct * pose[3 + col];
      (*axes)[6 + col] = pose[6 + col];
    }
    // The middle of the fetus's length (rump to crown) at the sac's centre, so that a fetus lying
    // across the narrower sac still fits.
    shift[0] = -0.5 * ((trunk.centre[0] - trunk.radii[0]) + (head.centre[0] + head.radii[0]));
  }
  const auto place = [&](const Vec& local) {
    if (!axes) return add(centre, rotate_z(local, yaw));
    return add(centre, times(*axes, add(local, shift)));
  };
  g.trunk = trunk, g.head = head;
  for (PhantomGeometry::Ellipsoid* e : {&g.trunk, &g.head}) {
    e->centre = place(e->centre);
    e->yaw = axes ? 0 : yaw;
    e->axes = axes;
  }
  for (int i = 0; i < 4; ++i) g.limbs[i] = {place(limbs[i].a), place(limbs[i].b), limbs[i].radius};
  return g;
}

PhantomGeometry phantom_geometry(const PhantomSettings& s) {
  return phantom_geometry(s.seed, s.fetus_offset_mm, s.fetus_orientation, settings_growth(s));
}

Phantom make_phantom(const PhantomSettings& s) {
  if (!(s.spacing_mm > 0)) throw std::invalid_argument("phantom: the spacing must be positive");
  Phantom p;
  const FetalGrowth growth = settings_growth(s);
  p.geometry = phantom_geometry(s);
  std::array<int, 3> n{};
  double voxels = 1;
  for (int d = 0; d < 3; ++d) {
    if (!(s.size_mm[d] > 0)) throw std::invalid_argument("phantom: the size must be positive");
    n[d] = std::max(1, static_cast<int>(std::ceil(growth.uterus * s.size_mm[d] / s.spacing_mm)));
    voxels *= n[d];
  }
  if (voxels > std::numeric_limits<int>::max())
    throw std::invalid_argument("phantom: " + std::to_string(voxels) + " voxels are too many; use a coarser spacing");
  for (Volume<std::uint8_t>* v : {&p.labels, &p.image}) {
    v->dimensions = n;
    v->spacing_mm = {s.spacing_mm, s.spacing_mm, s.spacing_mm};
    for (int d = 0; d < 3; ++d) v->origin_mm[d] = -0.5 * (n[d] - 1) * s.spacing_mm;
    v->data.assign(std::size_t(voxels), 0);
  }
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) p.labels.data[p.labels.index(i, j, k)] = p.geometry.label_at(p.labels.position_mm(i, j, k));

  // Speckle: |complex Gaussian| of a white field smoothed by a Gaussian kernel w, divided by its mean
  // (each component then has variance sum w^2; |z| is Rayleigh with mean sigma sqrt(pi/2)).
  std::vector<float> speckle;
  if (s.speckle) {
    Dice dice(s.seed ^ 0x9e3779b9u);
    const std::size_t count = static_cast<std::size_t>(voxels);
    std::vector<float> re(count), im(count);
    for (std::size_t v = 0; v < re.size(); ++v) re[v] = static_cast<float>(dice.normal()), im[v] = static_cast<float>(dice.normal());
    const auto w = gaussian_kernel(std::max(0.3, s.speckle_size_mm / s.spacing_mm / 2));
    double w2 = 0;
    for (double x : w) w2 += x * x;
    for (int axis = 0; axis < 3; ++axis)
      convolve_axis(re, n, axis, w, Faces::periodic), convolve_axis(im, n, axis, w, Faces::periodic);
    const double mean = std::sqrt(w2 * w2 * w2) * std::sqrt(M_PI / 2);
    speckle.resize(re.size());
    for (std::size_t v = 0; v < re.size(); ++v) speckle[v] = static_cast<float>(std::hypot(re[v], im[v]) / mean);
  }

  // Beams go down -z from the top face: attenuation with depth, and the energy each interface
  // reflects is missing below it.
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i) {
      double transmitted = 1;
      for (int k = n[2] - 1; k >= 0; --k) {
        const std::size_t v = p.labels.index(i, j, k);
        const std::uint8_t label = p.labels.data[v];
        if (s.shadowing && k < n[2] - 1) transmitted *= 1 - reflectance(p.labels.data[p.labels.index(i, j, k + 1)], label);
        const double depth = (n[2] - 1 - k) * s.spacing_mm;
        double value = echogenicity(label) * std::exp(-s.attenuation_per_mm * depth) * transmitted;
        if (s.speckle) value *= speckle[v];
        p.image.data[v] = static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
      }
    }
  return p;
}

}  // namespace fetouch::imaging

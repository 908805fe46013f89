#include "imaging/segmentation.h"

#include "imaging/separable_filter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace fetouch::imaging {

namespace {

template <class T, class U>
Volume<T> like(const Volume<U>& v) {
  Volume<T> out;
  out.dimensions = v.dimensions, out.spacing_mm = v.spacing_mm, out.origin_mm = v.origin_mm, out.direction = v.direction;
  out.data.assign(v.data.size(), T{});
  return out;
}

bool on_face(const std::array<int, 3>& n, int i, int j, int k) {
  return i == 0 || j == 0 || k == 0 || i == n[0] - 1 || j == n[1] - 1 || k == n[2] - 1;
}

// Labels the 6-connected components of the voxels where `inside(value)`; returns the label per
// voxel (0 outside) and each component's size and whether it touches a face.
template <class Inside>
std::vector<int> label_components(const Mask& m, Inside inside, std::vector<std::size_t>& sizes, std::vector<bool>& touches) {
  const auto& n = m.dimensions;
  std::vector<int> label(m.data.size(), 0);
  sizes.assign(1, 0);
  touches.assign(1, false);
  std::vector<std::size_t> stack;
  for (std::size_t start = 0; start < m.data.size(); ++start) {
    if (label[start] != 0 || !inside(m.data[start])) continue;
    const int id = static_cast<int>(sizes.size());
    sizes.push_back(0);
    touches.push_back(false);
    label[start] = id;
    stack.push_back(start);
    while (!stack.empty()) {
      const std::size_t a = stack.back();
      stack.pop_back();
      ++sizes[id];
      const int i = static_cast<int>(a % n[0]), j = static_cast<int>((a / n[0]) % n[1]), k = static_cast<int>(a / (std::size_t(n[0]) * n[1]));
      if (on_face(n, i, j, k)) touches[id] = true;
      const int offsets[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
      for (const auto& o : offsets) {
        const int ii = i + o[0], jj = j + o[1], kk = k + o[2];
        if (ii < 0 || jj < 0 || kk < 0 || ii >= n[0] || jj >= n[1] || kk >= n[2]) continue;
        const std::size_t b = m.index(ii, jj, kk);
        if (label[b] == 0 && inside(m.data[b])) label[b] = id, stack.push_back(b);
      }
    }
  }
  return label;
}

}  // namespace

Volume<float> gaussian_smooth(const Volume<float>& v, double sigma_mm) {
  Volume<float> out = v;
  if (!(sigma_mm > 0)) return out;
  for (int axis = 0; axis < 3; ++axis) {
    convolve_axis(out.data, v.dimensions, axis, gaussian_kernel(sigma_mm / v.spacing_mm[axis]), Faces::renormalised);
  }
  return out;
}

Volume<float> median3(const Volume<float>& v) {
  Volume<float> out = v;
  const auto& n = v.dimensions;
  std::array<float, 27> window;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        int count = 0;
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int ii = i + di, jj = j + dj, kk = k + dk;
              if (ii < 0 || jj < 0 || kk < 0 || ii >= n[0] || jj >= n[1] || kk >= n[2]) continue;
              window[count++] = v.data[v.index(ii, jj, kk)];
            }
        std::nth_element(window.begin(), window.begin() + count / 2, window.begin() + count);
        out.data[v.index(i, j, k)] = window[count / 2];
      }
  return out;
}

Volume<float> compensate_depth(const Volume<float>& v, double attenuation_per_mm) {
  Volume<float> out = v;
  const auto& n = v.dimensions;
  for (int k = 0; k < n[2]; ++k) {
    const float gain = static_cast<float>(std::exp(attenuation_per_mm * (n[2] - 1 - k) * v.spacing_mm[2]));
    for (std::size_t a = std::size_t(k) * n[0] * n[1]; a < std::size_t(k + 1) * n[0] * n[1]; ++a) out.data[a] *= gain;
  }
  return out;
}

Mask threshold(const Volume<float>& v, float low, float high) {
  Mask m = like<std::uint8_t>(v);
  for (std::size_t a = 0; a < v.data.size(); ++a) m.data[a] = v.data[a] >= low && v.data[a] <= high;
  return m;
}

Mask select_labels(const Volume<float>& labels_map, const std::vector<int>& labels) {
  Mask m = like<std::uint8_t>(labels_map);
  for (std::size_t a = 0; a < labels_map.data.size(); ++a)
    m.data[a] = std::find(labels.begin(), labels.end(), static_cast<int>(labels_map.data[a])) != labels.end();
  return m;
}

Mask connected_component(const Mask& mask, ComponentChoice choice, std::array<int, 3> seed) {
  std::vector<std::size_t> sizes;
  std::vector<bool> touches;
  const std::vector<int> label = label_components(mask, [](std::uint8_t x) { return x != 0; }, sizes, touches);
  int chosen = 0;
  if (choice == ComponentChoice::containing_seed) {
    for (int d = 0; d < 3; ++d)
      if (seed[d] < 0 || seed[d] >= mask.dimensions[d]) throw std::runtime_error("segmentation: the seed is outside the volume");
    chosen = label[mask.index(seed[0], seed[1], seed[2])];
    if (chosen == 0) throw std::runtime_error("segmentation: the seed voxel is not in the thresholded region");
  } else {
    for (std::size_t c = 1; c < sizes.size(); ++c)
      if ((choice == ComponentChoice::largest || !touches[c]) && (chosen == 0 || sizes[c] > sizes[chosen])) chosen = static_cast<int>(c);
    if (chosen == 0)
      throw std::runtime_error(choice == ComponentChoice::largest
                                   ? "segmentation is empty: no voxel passed the threshold"
                                   : "segmentation is empty: every region above the threshold touches the volume's faces");
  }
  Mask out = like<std::uint8_t>(mask);
  for (std::size_t a = 0; a < label.size(); ++a) out.data[a] = label[a] == chosen;
  return out;
}

namespace {

Mask morph(const Mask& m, int radius, bool dilate) {
  Mask out = like<std::uint8_t>(m);
  const auto& n = m.dimensions;
  std::vector<std::array<int, 3>> ball;
  for (int dk = -radius; dk <= radius; ++dk)
    for (int dj = -radius; dj <= radius; ++dj)
      for (int di = -radius; di <= radius; ++di)
        if (di * di + dj * dj + dk * dk <= radius * radius) ball.push_back({di, dj, dk});
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        bool value = !dilate;
        for (const auto& o : ball) {
          const int ii = i + o[0], jj = j + o[1], kk = k + o[2];
          const bool in = ii >= 0 && jj >= 0 && kk >= 0 && ii < n[0] && jj < n[1] && kk < n[2];
          const bool set = in && m.data[m.index(ii, jj, kk)];
          if (dilate && set) { value = true; break; }
          if (!dilate && !set) { value = false; break; }
        }
        out.data[m.index(i, j, k)] = value;
      }
  return out;
}

}  // namespace

Mask close(const Mask& mask, int radius) {
  if (radius <= 0) return mask;
  // Outside the volume counts as background.
  return morph(morph(mask, radius, true), radius, false);
}

Mask dilate(const Mask& mask, int radius) { return radius <= 0 ? mask : morph(mask, radius, true); }

Mask fill_holes(const Mask& mask) {
  std::vector<std::size_t> sizes;
  std::vector<bool> touches;
  const std::vector<int> label = label_components(mask, [](std::uint8_t x) { return x == 0; }, sizes, touches);
  Mask out = mask;
  for (std::size_t a = 0; a < label.size(); ++a)
    if (label[a] != 0 && !touches[label[a]]) out.data[a] = 1;  // background enclosed by the object
  return out;
}

Mask segment_fetus(const Volume<float>& image, const FetusSegmentation& s) {
  Volume<float> v = gaussian_smooth(image, s.smoothing_mm);
  if (s.attenuation_per_mm > 0) v = compensate_depth(v, s.attenuation_per_mm);
  // The low threshold's object, holes filled, less the band by which its boundary lies outside the
  // high threshold's: its interior (the brain inside the skull) joins the high threshold's mask.
  const Mask low = fill_holes(close(
      connected_component(threshold(v, s.low_threshold, 1e30f), ComponentChoice::largest_interior), s.closing_radius));
  const Mask interior = morph(low, s.closing_radius, /*dilate=*/false);
  Mask high = threshold(v, s.threshold, 1e30f);
  for (std::size_t a = 0; a < high.data.size(); ++a)
    if (interior.data[a]) high.data[a] = 1;
  return fill_holes(close(connected_component(high, ComponentChoice::largest_interior), s.closing_radius));
}

Mask segment_tissue(const Volume<float>& v, const TissueSegmentation& s, float* threshold_used) {
  if (!s.labels.empty()) return fill_holes(connected_component(select_labels(v, s.labels), ComponentChoice::largest));
  if (s.fetus) return segment_fetus(v, FetusSegmentation{});
  const Volume<float> smooth = s.smoothing == TissueSegmentation::Smoothing::gaussian ? gaussian_smooth(v, s.smoothing_mm)
                               : s.smoothing == TissueSegmentation::Smoothing::median ? median3(v)
                                                                                      : v;
  float t = 0;
  if (s.threshold) {
    t = *s.threshold;
  } else if (s.threshold_percentile) {
    if (!(*s.threshold_percentile >= 0 && *s.threshold_percentile <= 100))
      throw std::invalid_argument("the threshold percentile must be from 0 to 100, not " + std::to_string(*s.threshold_percentile));
    std::vector<float> values = smooth.data;
    const std::size_t at = std::min(values.size() - 1, static_cast<std::size_t>(*s.threshold_percentile / 100 * double(values.size())));
    std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(at), values.end());
    t = values[at];
  } else {
    std::vector<float> sorted = smooth.data;
    std::sort(sorted.begin(), sorted.end());
    const float low = sorted[sorted.size() / 20], high = sorted[sorted.size() * 19 / 20];
    if (!(high > low))
      throw std::runtime_error("no contrast to segment: 90 % of the voxels have the intensity " + std::to_string(low) +
                               " (a blank or constant volume); give --threshold or --labels if this is meant");
    t = 0.5f * (low + high);
  }
  if (threshold_used) *threshold_used = t;
  const Mask region = connected_component(threshold(smooth, t, 1e30f), ComponentChoice::largest);
  return fill_holes(close(region, s.closing));
}

double dice(const Mask& a, const Mask& b) {
  if (a.dimensions != b.dimensions) throw std::invalid_argument("dice: the masks differ in size");
  std::size_t both = 0, na = 0, nb = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    both += a.data[i] && b.data[i];
    na += a.data[i] != 0;
    nb += b.data[i] != 0;
  }
  return na + nb == 0 ? 1.0 : 2.0 * double(both) / double(na + nb);
}

}  // namespace fetouch::imaging

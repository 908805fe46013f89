#include "imaging/reconstruction.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "imaging/volume_header.h"
#include "imaging/volume_io.h"

namespace fetouch::imaging {

namespace {

Matrix4 multiply(const Matrix4& a, const Matrix4& b) {
  Matrix4 c{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) c[4 * i + j] += a[4 * i + k] * b[4 * k + j];
  return c;
}

// The inverse of a rigid transform [R t; 0 1]: [R' -R't; 0 1].
Matrix4 rigid_inverse(const Matrix4& m) {
  Matrix4 r{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r[4 * i + j] = m[4 * j + i];
    r[4 * i + 3] = -(m[i] * m[3] + m[4 + i] * m[7] + m[8 + i] * m[11]);
  }
  r[15] = 1;
  return r;
}

std::array<double, 3> apply(const Matrix4& m, double x, double y) {
  return {m[0] * x + m[1] * y + m[3], m[4] * x + m[5] * y + m[7], m[8] * x + m[9] * y + m[11]};
}

bool parse_matrix(const std::string& text, Matrix4& m) {
  std::istringstream in(text);
  for (double& v : m)
    if (!(in >> v) || !std::isfinite(v)) return false;
  double extra;
  return !(in >> extra);
}

// The attributes of one XML start tag (the text between "<Name" and ">"), name to value; quotes '
// or ". A loop over characters, not a regular expression: std::regex recurses per character and a
// long attribute overflowed the stack. False if the tag is malformed.
bool tag_attributes(const std::string& tag, std::map<std::string, std::string>& out) {
  std::size_t i = 0;
  const auto space = [&] {
    while (i < tag.size() && std::isspace(static_cast<unsigned char>(tag[i]))) ++i;
  };
  for (;;) {
    space();
    if (i >= tag.size() || tag[i] == '/') return true;
    const std::size_t name_start = i;
    while (i < tag.size() && tag[i] != '=' && !std::isspace(static_cast<unsigned char>(tag[i]))) ++i;
    const std::string name = tag.substr(name_start, i - name_start);
    space();
    if (name.empty() || i >= tag.size() || tag[i] != '=') return false;
    ++i;
    space();
    if (i >= tag.size() || (tag[i] != '"' && tag[i] != '\'')) return false;
    const char quote = tag[i++];
    const std::size_t end = tag.find(quote, i);
    if (end == std::string::npos) return false;
    out[name] = tag.substr(i, end - i);
    i = end + 1;
  }
}

// A value as quoted in a message: at most 80 characters, control and non-ASCII bytes as '?'.
std::string shown(const std::string& text) {
  std::string out = text.size() <= 80 ? text : text.substr(0, 77) + "...";
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return out;
}

// Why a 4 x 4 matrix is not a plausible transform, or "" when it is: an affine last row, a
// translation within `max_shift_mm`, and a linear part whose columns have lengths in [min_scale,
// max_scale] (1 for a rigid pose; mm per pixel for a calibration) and are orthogonal: the cosine
// of the angle between two at most `max_cosine` (a calibration fit leaves a few per cent).
std::string implausible_transform(const Matrix4& m, double min_scale, double max_scale, double max_shift_mm,
                                  double max_cosine) {
  if (m[12] != 0 || m[13] != 0 || m[14] != 0 || m[15] != 1) return "its last row is not 0 0 0 1 (not an affine transform)";
  for (int r = 0; r < 3; ++r)
    if (!(std::abs(m[4 * r + 3]) <= max_shift_mm)) return "a translation beyond " + std::to_string(int(max_shift_mm / 1000)) + " m";
  double length[3];
  for (int c = 0; c < 3; ++c) {
    length[c] = std::sqrt(m[c] * m[c] + m[4 + c] * m[4 + c] + m[8 + c] * m[8 + c]);
    if (!(length[c] >= min_scale && length[c] <= max_scale)) {
      std::ostringstream why;
      why << "column " << c + 1 << " has length " << length[c] << "; expected " << min_scale << " to " << max_scale;
      return why.str();
    }
  }
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b) {
      const double dot = m[a] * m[b] + m[4 + a] * m[4 + b] + m[8 + a] * m[8 + b];
      if (std::abs(dot) > max_cosine * length[a] * length[b]) return "its axes are not orthogonal (sheared)";
    }
  return "";
}

}  // namespace

TrackedSweep read_tracked_sweep(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw std::runtime_error(name + ": not a regular file (a sweep is a .igs.mha file, not a folder, FIFO or device)");
  std::map<std::string, std::string> fields = text_header(path, '=');
  TrackedSweep sweep;
  const Volume<float> pixels = read_volume(path);
  sweep.frames.dimensions = pixels.dimensions;
  sweep.frames.spacing_mm = {1, 1, 1};
  sweep.frames.data.resize(pixels.data.size());
  std::transform(pixels.data.begin(), pixels.data.end(), sweep.frames.data.begin(),
                 [](float v) { return static_cast<std::uint8_t>(std::clamp(v, 0.0f, 255.0f)); });
  const int frames = pixels.dimensions[2];
  sweep.poses.resize(frames);
  for (int f = 0; f < frames; ++f) {
    char prefix[32];
    std::snprintf(prefix, sizeof prefix, "Seq_Frame%04d_", f);
    auto& pose = sweep.poses[f];
    pose.valid = true;
    for (const auto& [suffix, matrix] : {std::pair<const char*, Matrix4*>{"ProbeToTrackerTransform", &pose.probe_to_tracker},
                                         {"ReferenceToTrackerTransform", &pose.reference_to_tracker}}) {
      const std::string key = std::string(prefix) + suffix;
      const auto found = fields.find(key);
      if (found == fields.end()) throw std::runtime_error(name + ": frame " + std::to_string(f) + " has no " + key);
      if (!parse_matrix(found->second, *matrix))
        throw std::runtime_error(name + ": " + key + " is not 16 finite numbers: '" + shown(found->second) + "'");
      const auto status = fields.find(key + "Status");
      if (status != fields.end() && status->second != "OK") {
        pose.valid = false;  // an untracked frame's matrix means nothing
        continue;
      }
      // A tracked pose is rigid: a rotation (columns of length 1, within 2 %) and a shift within 100 m.
      const std::string why = implausible_transform(*matrix, 0.98, 1.02, 1e5, 0.02);
      if (!why.empty()) throw std::runtime_error(name + ": " + key + " is not a rigid pose: " + why);
    }
  }
  return sweep;
}

Matrix4 read_image_to_probe(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) throw std::runtime_error(name + ": cannot open the calibration (not a file)");
  // A PLUS configuration is a few kilobytes; anything past 64 MB is not one.
  if (std::filesystem::file_size(path, error) > (64u << 20))
    throw std::runtime_error(name + ": over 64 MB, not a PLUS configuration file");
  std::ifstream in(path);
  if (!in) throw std::runtime_error(name + ": cannot open the calibration");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // The root element (after the XML declaration, comments and a byte-order mark) is PlusConfiguration.
  std::size_t root = text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  for (;;) {
    root = text.find_first_not_of(" \t\r\n", root);
    if (root != std::string::npos && text.compare(root, 4, "<!--") == 0) root = text.find("-->", root);
    else if (root != std::string::npos && text.compare(root, 2, "<?") == 0) root = text.find("?>", root);
    else break;
    if (root != std::string::npos) root += 2;
  }
  if (root == std::string::npos || text.compare(root, 18, "<PlusConfiguration") != 0)
    throw std::runtime_error(name + ": not a PLUS configuration file (expected the root element <PlusConfiguration>, found '" +
                             shown(root == std::string::npos ? std::string() : text.substr(root, 24)) + "')");
  std::optional<Matrix4> found;
  std::size_t found_line = 0;
  for (std::size_t at = text.find("<Transform"); at != std::string::npos; at = text.find("<Transform", at + 1)) {
    const std::size_t begin = at + std::string("<Transform").size();
    if (begin < text.size() && !std::isspace(static_cast<unsigned char>(text[begin])) && text[begin] != '>' &&
        text[begin] != '/')
      continue;  // <TransformSomethingElse
    const std::size_t end = text.find('>', begin);
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
    std::map<std::string, std::string> attributes;
    if (end == std::string::npos || !tag_attributes(text.substr(begin, end - begin), attributes))
      throw std::runtime_error(name + ":" + std::to_string(line) + ": a malformed <Transform> element");
    if (attributes["From"] != "Image" || attributes["To"] != "Probe") continue;
    const auto matrix = attributes.find("Matrix");
    if (matrix == attributes.end())
      throw std::runtime_error(name + ":" + std::to_string(line) + ": the Image-to-Probe <Transform> has no Matrix");
    Matrix4 m;
    if (!parse_matrix(matrix->second, m))
      throw std::runtime_error(name + ":" + std::to_string(line) + ": the Image-to-Probe matrix is not 16 finite numbers: '" +
                               shown(matrix->second) + "'");
    // Pixels to millimetres: a rotation times the pixel size (0.001 to 10 mm), within 10 m.
    const std::string why = implausible_transform(m, 1e-3, 10, 1e4, 0.2);
    if (!why.empty())
      throw std::runtime_error(name + ":" + std::to_string(line) + ": the Image-to-Probe matrix is not a calibration: " + why +
                               " (a rotation times the pixel size in mm, 0.001 to 10)");
    if (found)
      throw std::runtime_error(name + ":" + std::to_string(line) + ": a second Image-to-Probe transform (the first is on line " +
                               std::to_string(found_line) + "); keep one");
    found = m, found_line = line;
  }
  if (found) return *found;
  throw std::runtime_error(name + ": no <Transform From=\"Image\" To=\"Probe\" Matrix=\"...\"> element");
}

Reconstruction reconstruct(const TrackedSweep& sweep, const Matrix4& image_to_probe, const ReconstructionSettings& s) {
  if (!(s.spacing_mm > 0)) throw std::invalid_argument("reconstruction: the spacing must be positive");
  const int width = sweep.frames.dimensions[0], height = sweep.frames.dimensions[1];
  std::vector<Matrix4> to_reference;
  std::vector<int> frame_index;
  Reconstruction out;
  for (int f = 0; f < static_cast<int>(sweep.poses.size()); ++f) {
    if (!sweep.poses[f].valid) {
      ++out.frames_skipped;
      continue;
    }
    to_reference.push_back(
        multiply(multiply(rigid_inverse(sweep.poses[f].reference_to_tracker), sweep.poses[f].probe_to_tracker), image_to_probe));
    frame_index.push_back(f);
  }
  out.frames_used = static_cast<int>(to_reference.size());
  if (to_reference.empty()) throw std::runtime_error("reconstruction: no frame has a valid pose");
  // The box of all frames' corners (pixel centres).
  std::array<double, 3> lo{}, hi{};
  lo.fill(std::numeric_limits<double>::max());
  hi.fill(std::numeric_limits<double>::lowest());
  for (const Matrix4& m : to_reference)
    for (const double x : {0.0, double(width - 1)})
      for (const double y : {0.0, double(height - 1)}) {
        const auto p = apply(m, x, y);
        for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], p[d]), hi[d] = std::max(hi[d], p[d]);
      }
  Volume<std::uint8_t>& v = out.volume;
  double voxels = 1;
  for (int d = 0; d < 3; ++d) {
    v.dimensions[d] = static_cast<int>(std::floor((hi[d] - lo[d]) / s.spacing_mm)) + 1;
    v.spacing_mm[d] = s.spacing_mm;
    v.origin_mm[d] = lo[d];
    voxels *= v.dimensions[d];
  }
  if (voxels > 1e9) throw std::invalid_argument("reconstruction: " + std::to_string(voxels) + " voxels; use a coarser spacing");
  const std::size_t count = static_cast<std::size_t>(voxels);
  std::vector<float> sum(count, 0.0f), weight(count, 0.0f);
  const auto paste = [&](std::size_t at, float value, float w) {
    if (s.maximum) {
      sum[at] = weight[at] > 0 ? std::max(sum[at], value) : value;
      weight[at] = std::max(weight[at], w);
    } else {
      sum[at] += w * value;
      weight[at] += w;
    }
  };
  for (std::size_t k = 0; k < to_reference.size(); ++k) {
    const Matrix4& m = to_reference[k];
    const std::uint8_t* frame = sweep.frames.data.data() + std::size_t(frame_index[k]) * width * height;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const auto p = apply(m, x, y);
        double g[3];
        for (int d = 0; d < 3; ++d) g[d] = (p[d] - v.origin_mm[d]) / s.spacing_mm;
        const float value = frame[std::size_t(y) * width + x];
        if (!s.linear) {
          const int i = static_cast<int>(std::lround(g[0])), j = static_cast<int>(std::lround(g[1])),
                    l = static_cast<int>(std::lround(g[2]));
          if (i < 0 || j < 0 || l < 0 || i >= v.dimensions[0] || j >= v.dimensions[1] || l >= v.dimensions[2]) continue;
          paste(v.index(i, j, l), value, 1.0f);
          continue;
        }
        const int i0 = static_cast<int>(std::floor(g[0])), j0 = static_cast<int>(std::floor(g[1])),
                  l0 = static_cast<int>(std::floor(g[2]));
        const double fx = g[0] - i0, fy = g[1] - j0, fz = g[2] - l0;
        for (int c = 0; c < 8; ++c) {
          const int i = i0 + (c & 1), j = j0 + ((c >> 1) & 1), l = l0 + ((c >> 2) & 1);
          if (i < 0 || j < 0 || l < 0 || i >= v.dimensions[0] || j >= v.dimensions[1] || l >= v.dimensions[2]) continue;
          const double w = ((c & 1) ? fx : 1 - fx) * (((c >> 1) & 1) ? fy : 1 - fy) * (((c >> 2) & 1) ? fz : 1 - fz);
          if (w > 0) paste(v.index(i, j, l), value, static_cast<float>(w));
        }
      }
  }
  v.data.assign(count, 0);
  std::vector<bool> filled(count, false);
  for (std::size_t a = 0; a < count; ++a)
    if (weight[a] > 0) {
      const double value = s.maximum ? sum[a] : sum[a] / weight[a];
      v.data[a] = static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
      filled[a] = true;
    }
  std::size_t filled_count = std::count(filled.begin(), filled.end(), true);
  if (s.fill_holes) {
    // A hole surrounded by filled voxels (more than half its neighbourhood) takes their mean.
    const int r = std::max(1, s.fill_radius);
    std::vector<std::uint8_t> result = v.data;
    for (int l = 0; l < v.dimensions[2]; ++l)
      for (int j = 0; j < v.dimensions[1]; ++j)
        for (int i = 0; i < v.dimensions[0]; ++i) {
          const std::size_t a = v.index(i, j, l);
          if (filled[a]) continue;
          double total = 0;
          int n = 0, neighbours = 0;
          for (int dl = -r; dl <= r; ++dl)
            for (int dj = -r; dj <= r; ++dj)
              for (int di = -r; di <= r; ++di) {
                const int ii = i + di, jj = j + dj, ll = l + dl;
                if (ii < 0 || jj < 0 || ll < 0 || ii >= v.dimensions[0] || jj >= v.dimensions[1] || ll >= v.dimensions[2]) continue;
                ++neighbours;
                const std::size_t b = v.index(ii, jj, ll);
                if (filled[b]) total += v.data[b], ++n;
              }
          if (2 * n > neighbours) {
            result[a] = static_cast<std::uint8_t>(std::lround(total / n));
            ++filled_count;
          }
        }
    v.data.swap(result);
  }
  out.filled_fraction = double(filled_count) / double(count);
  return out;
}

}  // namespace fetouch::imaging

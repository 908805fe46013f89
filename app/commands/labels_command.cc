// `fetouch labels`: a label map for `fetouch mesh --regions` made from segmentations of real
// volumes (docs/meshing.md): each layer a volume segmented as `fetouch mesh` segments one (smoothing,
// a threshold, the largest piece, closing, holes filled), layer k drawn as label k inside layer k-1.
// With --smooth the masks are first smoothed at a scale the elements can follow: a head at 1 mm
// voxels has nostrils and a 1 mm staircase that no 8 mm element resolves.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "app/json_writer.h"
#include "app/output_guard.h"
#include "imaging/segmentation.h"
#include "imaging/volume_io.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;

struct Layer {
  std::string path;
  std::optional<float> threshold;
  int closing = 2;
};

struct LabelsOptions {
  std::string out;
  std::vector<std::string> layers;
  double smooth_mm = 0;
  int shell = 3;  // voxels of each layer kept around the next
  bool json = false;
};

// FILE[:threshold=T][:close=C], the keys read from the right, so that a path may hold colons.
Layer parse_layer(const std::string& text) {
  Layer layer;
  std::string rest = text;
  for (;;) {
    const std::size_t colon = rest.rfind(':');
    if (colon == std::string::npos) break;
    const std::string field = rest.substr(colon + 1);
    const std::size_t equals = field.find('=');
    if (equals == std::string::npos) break;
    const std::string key = field.substr(0, equals), value = field.substr(equals + 1);
    if (key != "threshold" && key != "close") break;
    std::size_t used = 0;
    double number = 0;
    try {
      number = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != value.size() || !std::isfinite(number))
      throw std::invalid_argument("layer " + text + ": " + key + " must be a number, not '" + value + "'");
    if (key == "threshold") layer.threshold = static_cast<float>(number);
    if (key == "close") {
      if (number < 0 || number > 10 || number != std::floor(number))
        throw std::invalid_argument("layer " + text + ": close must be a whole number of voxels from 0 to 10, not " + value);
      layer.closing = static_cast<int>(number);
    }
    rest = rest.substr(0, colon);
  }
  layer.path = rest;
  return layer;
}

// The mask smoothed by a Gaussian of sigma_mm and cut at one half, on a grid grown by a margin of
// background (the smoothing's reach), so that where the volume cut the object (a head at the neck)
// its end is rounded like the rest, not left as a flat face meeting the sides at an edge.
imaging::Mask smooth_mask(const imaging::Mask& mask, double sigma_mm, int margin) {
  imaging::Volume<float> grown;
  grown.dimensions = {mask.dimensions[0] + 2 * margin, mask.dimensions[1] + 2 * margin, mask.dimensions[2] + 2 * margin};
  grown.spacing_mm = mask.spacing_mm;
  grown.direction = mask.direction;
  grown.origin_mm = mask.position_mm(-margin, -margin, -margin);
  grown.data.assign(std::size_t(grown.dimensions[0]) * grown.dimensions[1] * grown.dimensions[2], 0.0f);
  for (int k = 0; k < mask.dimensions[2]; ++k)
    for (int j = 0; j < mask.dimensions[1]; ++j)
      for (int i = 0; i < mask.dimensions[0]; ++i)
        grown.data[grown.index(i + margin, j + margin, k + margin)] = mask.data[mask.index(i, j, k)] ? 1.0f : 0.0f;
  return imaging::threshold(imaging::gaussian_smooth(grown, sigma_mm), 0.5f, 2.0f);
}

bool same_grid(const imaging::Volume<float>& a, const imaging::Volume<float>& b) {
  for (int d = 0; d < 3; ++d)
    if (a.dimensions[d] != b.dimensions[d] || std::abs(a.spacing_mm[d] - b.spacing_mm[d]) > 1e-6 * a.spacing_mm[d] ||
        std::abs(a.origin_mm[d] - b.origin_mm[d]) > 1e-3 * a.spacing_mm[d])
      return false;
  for (int e = 0; e < 9; ++e)
    if (std::abs(a.direction[e] - b.direction[e]) > 1e-6) return false;
  return true;
}

int run_labels(const LabelsOptions& o) {
  const fs::path out(o.out);
  const std::string extension = out.extension().string();
  if (extension != ".mha" && extension != ".vti")
    throw std::invalid_argument("--out must end in .mha or .vti (a label map `fetouch mesh` reads): " + o.out);
  if (o.layers.size() > 255) throw std::invalid_argument("at most 255 layers (labels 1 to 255), not " + std::to_string(o.layers.size()));
  std::vector<Layer> layers;
  for (const std::string& text : o.layers) layers.push_back(parse_layer(text));
  std::vector<NamedInput> inputs;
  for (std::size_t k = 0; k < layers.size(); ++k) inputs.emplace_back(layers[k].path, "layer " + std::to_string(k + 1));
  refuse_overwriting({out}, inputs);
  const auto start = std::chrono::steady_clock::now();
  imaging::Volume<float> first;
  std::vector<imaging::Mask> masks;
  std::vector<float> thresholds;
  for (std::size_t k = 0; k < layers.size(); ++k) {
    const Layer& layer = layers[k];
    std::fprintf(stderr, "layer %zu: segmenting %s\n", k + 1, layer.path.c_str());
    imaging::Volume<float> volume = imaging::read_volume(layer.path);
    if (k == 0) first = volume;
    else if (!same_grid(first, volume))
      throw std::invalid_argument(layer.path + ": not on the grid of " + layers[0].path +
                                  " (dimensions, spacing, origin and directions must match)");
    imaging::TissueSegmentation settings;
    settings.threshold = layer.threshold;
    settings.closing = layer.closing;
    float used = 0;
    try {
      masks.push_back(imaging::segment_tissue(volume, settings, &used));
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(layer.path + ": " + e.what());
    }
    thresholds.push_back(used);
  }
  // Each layer holds the next with `shell` voxels around it: a brain that BET found where the head's
  // threshold missed the dark bone (by the ear) would otherwise reach the outside there, through no
  // head at all.
  for (std::size_t k = masks.size(); k-- > 1;) {
    const imaging::Mask grown = imaging::dilate(masks[k], o.shell);
    for (std::size_t v = 0; v < grown.data.size(); ++v) masks[k - 1].data[v] |= grown.data[v];
  }
  if (o.smooth_mm > 0) {
    const auto& h = first.spacing_mm;
    const int margin = static_cast<int>(std::ceil(3 * o.smooth_mm / *std::min_element(h.begin(), h.end()))) + 1;
    for (imaging::Mask& mask : masks) mask = smooth_mask(mask, o.smooth_mm, margin);
  }
  // Layer k + 1 is drawn where it lies inside layer k (all of it but what the smoothing rounded).
  imaging::Mask labels = masks[0];
  for (std::size_t k = 1; k < masks.size(); ++k)
    for (std::size_t v = 0; v < labels.data.size(); ++v)
      if (masks[k].data[v] && labels.data[v] == k) labels.data[v] = static_cast<std::uint8_t>(k + 1);
  std::vector<long> counts(layers.size() + 1, 0);
  for (const std::uint8_t l : labels.data) ++counts[l];
  for (std::size_t k = 1; k < counts.size(); ++k)  // nothing written
    if (counts[k] == 0)
      throw std::invalid_argument("label " + std::to_string(k) + " (" + layers[k - 1].path +
                                  ") has no voxel inside the layer before it");
  replace_when_written(out, [&](const fs::path& temporary) { imaging::write_volume(labels, temporary); });
  const double voxel_ml = labels.spacing_mm[0] * labels.spacing_mm[1] * labels.spacing_mm[2] * 1e-3;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (o.json) {
    JsonWriter json(std::cout);
    json.begin_object();
    json.key("out").value(out.string());
    json.key("dimensions").values(std::vector<double>(labels.dimensions.begin(), labels.dimensions.end()));
    json.key("spacing_mm").values(std::vector<double>(labels.spacing_mm.begin(), labels.spacing_mm.end()));
    json.key("origin_mm").values(std::vector<double>(labels.origin_mm.begin(), labels.origin_mm.end()));
    json.key("smooth_mm").value(o.smooth_mm);
    json.key("labels").begin_array();
    for (std::size_t k = 0; k < layers.size(); ++k) {
      json.begin_object();
      json.key("label").value(static_cast<long>(k + 1));
      json.key("volume").value(layers[k].path);
      json.key("threshold").value(static_cast<double>(thresholds[k]));
      json.key("closing").value(layers[k].closing);
      json.key("voxels").value(counts[k + 1]);
      json.key("volume_ml").value(counts[k + 1] * voxel_ml);
      json.end_object();
    }
    json.end_array();
    json.key("seconds").value(seconds);
    json.end_object();
    std::cout << "\n";
  } else {
    std::printf("%s: %d x %d x %d voxels of %.3g x %.3g x %.3g mm\n", out.string().c_str(), labels.dimensions[0],
                labels.dimensions[1], labels.dimensions[2], labels.spacing_mm[0], labels.spacing_mm[1], labels.spacing_mm[2]);
    for (std::size_t k = 0; k < layers.size(); ++k)
      std::printf("  label %zu: %s above %g, closed by %d voxels: %ld voxels, %.1f ml\n", k + 1, layers[k].path.c_str(),
                  thresholds[k], layers[k].closing, counts[k + 1], counts[k + 1] * voxel_ml);
    std::printf("  in %.1f s\n", seconds);
  }
  return kExitOk;
}

}  // namespace

void add_labels_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<LabelsOptions>();
  CLI::App* cmd = parent.add_subcommand("labels", "A label map of nested regions from segmentations of volumes, for `fetouch mesh --regions`");
  cmd->add_option("--out", o->out, "The label map (.mha or .vti)")->required();
  cmd->add_option("layers", o->layers,
                  "FILE[:threshold=T][:close=C] each, outermost first: a volume segmented as `fetouch mesh` segments "
                  "one (Gaussian 1 mm, the threshold T in its units or the default, the largest piece, closed by C "
                  "voxels (default 2), holes filled); layer k is label k, drawn inside layer k-1")
      ->required();
  cmd->add_option("--smooth", o->smooth_mm, "Smooth each layer's mask by a Gaussian of this sigma (mm) and cut it at one half "
                                             "(the map grows by the smoothing's reach of background)")
      ->check(CLI::Range(0.0, 50.0));
  cmd->add_option("--shell", o->shell, "Voxels of each layer kept around the next: a layer is grown to hold the next with this many around it")
      ->check(CLI::Range(0, 20));
  cmd->add_flag("--json", o->json, "Print the summary as JSON");
  cmd->footer("Example (Colin27 from Debian's mricron-data: the head, and the brain that BET extracted, as two labels):\n"
              "  fetouch labels --out head_brain.mha --smooth 3.5 \\\n"
              "      /usr/share/mricron/templates/ch2.nii.gz:threshold=20:close=5 /usr/share/mricron/templates/ch2bet.nii.gz:threshold=1\n"
              "  fetouch mesh head_brain.mha --regions head=1 brain=2 --surface conforming --size 8 --out head_brain.msh");
  cmd->callback([o, &exit_code] {
    try {
      exit_code = run_labels(*o);
    } catch (const std::exception& e) {  // a volume that cannot be read or segmented, a bad layer
      std::cerr << "error: " << e.what() << "\n";
      exit_code = kExitBadInput;
    }
  });
}

}  // namespace fetouch::app

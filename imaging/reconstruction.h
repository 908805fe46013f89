// Volume reconstruction from a tracked freehand sweep (PLUS conventions): 2D frames, each with the
// probe's and the reference's poses in the tracker's frame, and an Image-to-Probe calibration
// (pixel to mm). Each pixel (i, j) goes to the reference frame by
//   ImageToReference = inverse(ReferenceToTracker) * ProbeToTracker * ImageToProbe,
// and is pasted into a volume aligned with the reference axes, at a chosen spacing, covering every
// frame: nearest voxel or trilinear splatting (weights to the 8 surrounding voxels), compounded by
// the weighted mean or the maximum; voxels no pixel reached can be filled from their filled
// neighbours (holes between frames).
#pragma once

#include <array>
#include <filesystem>
#include <vector>

#include "imaging/phantom.h"

namespace fetouch::imaging {

using Matrix4 = std::array<double, 16>;  // row-major

struct TrackedSweep {
  Volume<std::uint8_t> frames;  // width x height x frame count
  struct Pose {
    Matrix4 probe_to_tracker{}, reference_to_tracker{};
    bool valid = false;  // both transforms' status OK
  };
  std::vector<Pose> poses;  // one per frame
};

// Reads a PLUS sequence file (.igs.mha / .seq.mha: a MetaImage with Seq_FrameNNNN_* header fields).
// Throws std::runtime_error naming the file and the field for a missing or malformed pose.
TrackedSweep read_tracked_sweep(const std::filesystem::path& path);

// The Image-to-Probe matrix of a PLUS configuration file (<Transform From="Image" To="Probe"
// Matrix="..."/>). Throws std::runtime_error naming the file when it is missing or malformed.
Matrix4 read_image_to_probe(const std::filesystem::path& path);

struct ReconstructionSettings {
  double spacing_mm = 0.5;
  bool linear = true;    // false: nearest voxel
  bool maximum = false;  // false: weighted mean
  bool fill_holes = true;
  int fill_radius = 1;   // voxels: a hole takes the mean of its filled neighbours within this distance
};

struct Reconstruction {
  Volume<std::uint8_t> volume;
  int frames_used = 0, frames_skipped = 0;
  double filled_fraction = 0;  // of the voxels, after hole filling
};

Reconstruction reconstruct(const TrackedSweep& sweep, const Matrix4& image_to_probe, const ReconstructionSettings& settings);

}  // namespace fetouch::imaging

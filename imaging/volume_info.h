// What a volume file says about itself, read from its header without loading the voxels.
// Images are in millimetres (their headers are); meshes and the simulation are in metres.
#pragma once

#include <array>
#include <filesystem>
#include <string>

namespace fetouch::imaging {

struct VolumeInfo {
  std::string format;  // "MetaImage", "VTK image data", "NRRD", "NIfTI", "DICOM series"
  std::array<int, 3> dimensions{0, 0, 0};
  std::array<double, 3> spacing_mm{0, 0, 0};
  std::array<double, 3> origin_mm{0, 0, 0};
  std::array<double, 9> direction{1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major; column c: index axis c
  int components = 0;
  std::string scalar_type;  // "unsigned char", "short", "float", ...

  double voxel_count() const;
  std::array<double, 3> extent_mm() const;  // dimensions x spacing
};

// Reads the header of a .mha/.mhd, .vti, .nrrd/.nhdr, .nii/.nii.gz/.hdr file or a folder holding a DICOM series
// (imaging/volume_io.cc reads both headers and volumes).
// Throws std::runtime_error naming the file and what is wrong with it.
VolumeInfo read_volume_info(const std::filesystem::path& path);

}  // namespace fetouch::imaging

// Reading and writing whole volumes: MetaImage (.mha, .mhd + raw; written compressed), VTK image
// data (.vti), NRRD (.nrrd, .nhdr; read only) and NIfTI-1 (.nii, .nii.gz, .hdr + .img; read only,
// imaging/nifti_io.h), by extension. Spacing and origin are kept (mm).
#pragma once

#include <cstdint>
#include <filesystem>

#include "imaging/phantom.h"

namespace fetouch::imaging {

// The first component of any scalar type, as float. Throws std::runtime_error naming the file and
// what is wrong (missing, unreadable, no voxels, dimensions that the data does not fill).
Volume<float> read_volume(const std::filesystem::path& path);

// Throws std::runtime_error naming the file if it cannot be written.
void write_volume(const Volume<std::uint8_t>& volume, const std::filesystem::path& path);

}  // namespace fetouch::imaging

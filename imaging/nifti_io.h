// NIfTI-1 volumes (.nii, .nii.gz, and .hdr + .img pairs), read here from the header the standard
// defines rather than by VTK's reader, so that every field is checked before a byte of data is
// trusted and the geometry follows the standard's rules exactly:
//   - the voxel-to-world map is the sform when sform_code > 0, else the qform (quaternion, qfac
//     from pixdim[0], qoffset) when qform_code > 0, else pixdim alone ("method 1");
//   - NIfTI's world is RAS (+x right, +y anterior); Fetouch's images are in DICOM's LPS, like
//     MetaImage, NRRD and DICOM series, so x and y change sign (a half turn about z): a NIfTI and a
//     DICOM series of one patient land in the same place;
//   - lengths in metres or micrometres (xyzt_units) are turned into millimetres;
//   - scl_slope and scl_inter, when the slope is set, give the values in the image's units (a CT's
//     Hounsfield units), so a threshold is in those units;
//   - a 4D (or higher) image: its first 3D volume.
#pragma once

#include <filesystem>

#include "imaging/phantom.h"
#include "imaging/volume_info.h"

namespace fetouch::imaging {

// True for .nii, .nii.gz, .hdr (and .hdr.gz) by name.
bool is_nifti_name(const std::filesystem::path& path);

// The header's geometry and type; throws std::runtime_error naming the file, the field and its
// value when the header is not a NIfTI-1 header or promises data the file does not hold.
VolumeInfo read_nifti_info(const std::filesystem::path& path);

// The first 3D volume, as float, scaled by scl_slope and scl_inter. The size bound every format
// keeps (imaging/volume_io.cc's check_plausible, at most 2^30 voxels) is checked by read_volume
// on read_nifti_info before this allocates.
Volume<float> read_nifti(const std::filesystem::path& path);

}  // namespace fetouch::imaging

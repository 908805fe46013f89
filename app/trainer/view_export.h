// What the trainer's views showed, in files other tools open: the tissue as shown (a .vtu of the
// reference mesh with the displacement the 3D view and the ultrasound image were made from) and the
// ultrasound image at its own resolution (an 8-bit grey PNG). `fetouch trainer --screenshot` writes
// both beside the screenshot, so that a bug report, a doc figure or a test can redo the image.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "app/trainer/trainer_session.h"

namespace fetouch::app::trainer {

// Points (the reference mesh), linear tetrahedra, point data `displacement` (m), cell data
// `material_id`, and field data `region_names` ("ID NAME" per named region). Throws
// std::runtime_error naming the file if it cannot be written.
void write_tissue_vtu(const MeshView& mesh, const std::vector<float>& displacement, const std::filesystem::path& file);

// Where a take's anatomy goes beside its recording: DIR/anatomy.vtu for DIR/take.h5 (an
// exercise's), DIR/STEM.anatomy.vtu for any other DIR/STEM.h5 (the trainer's ctrl+R takes).
inline std::filesystem::path anatomy_beside(const std::filesystem::path& recording) {
  const std::string stem = recording.stem().string();
  return recording.parent_path() / (stem == "take" ? std::string("anatomy.vtu") : stem + ".anatomy.vtu");
}

// A mesh written by write_tissue_vtu, read back as the views draw it: its tetrahedra (each its own
// cell), their regions and names, and its outer surface (the faces of one tetrahedron only); the
// displacement is not read. Throws std::runtime_error naming the file and what is wrong with it.
MeshView read_tissue_vtu(const std::filesystem::path& file);

// Row 0 on top. Throws std::runtime_error naming the file if it cannot be written.
void write_grey_png(const std::vector<std::uint8_t>& image, int columns, int rows, const std::filesystem::path& file);

}  // namespace fetouch::app::trainer

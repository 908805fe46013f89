// The trainer's ultrasound images, made on a thread of their own so that the window's render loop
// (the 3D view, under software OpenGL most of a tick) does not bound their rate: the window asks for
// the image of a frame's tissue in a plane at each of its ticks, the imager makes the newest asked
// while the window renders, and the window shows the newest finished at its next tick. A request
// not yet started is replaced by a newer one (the window never queues work it will not show).
//
// Neither the haptic nor the solver thread meets it: the window copies the displacement from its
// own snapshot. The thread runs at a lower priority (nice +5) than the solver's.
#pragma once

#include <array>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "app/trainer/deformed_slice.h"

namespace fetouch::app::trainer {

struct UltrasoundImage {
  long frame = -1;  // the solver frame whose tissue it shows
  SlicePlane plane;
  std::vector<std::uint8_t> pixels;  // plane.rows x plane.columns, row 0 on top
  std::vector<float> reference;      // X per pixel (DeformedSlicer::slice)
  double seconds = 0;                // what making it took
};

class UltrasoundImager {
 public:
  // The reference mesh (as DeformedSlicer takes it), the volume (null: the mesh's cross-section) and
  // its gain. Starts the thread.
  UltrasoundImager(std::vector<std::array<double, 3>> points, std::vector<std::array<unsigned int, 4>> tetrahedra,
                   std::vector<unsigned int> material, std::shared_ptr<const ReferenceVolume> volume, double gain);
  ~UltrasoundImager();  // stops and joins the thread
  UltrasoundImager(const UltrasoundImager&) = delete;
  UltrasoundImager& operator=(const UltrasoundImager&) = delete;

  // Asks for the image of `displacement` (3 per point; frame `frame`) in `plane`.
  void request(long frame, const std::vector<float>& displacement, const SlicePlane& plane);
  // The newest image finished since the last take, swapped into `image` (whose buffers go back to
  // the imager for reuse); false when none is new.
  bool take(UltrasoundImage& image);
  // The image made here and now (after the one in progress, if any): for exports that must show
  // exactly the tissue they are written beside.
  void make_now(long frame, const std::vector<float>& displacement, const SlicePlane& plane, UltrasoundImage& image);

 private:
  void run();

  std::shared_ptr<const ReferenceVolume> volume_;
  double gain_;
  std::mutex slicer_mutex_;  // the slicer is one, shared by the thread and make_now
  DeformedSlicer slicer_;
  std::mutex mutex_;  // the request and the finished image
  std::condition_variable wake_;
  bool stop_ = false, asked_ = false, finished_ = false;
  long asked_frame_ = -1;
  std::vector<float> asked_displacement_;
  SlicePlane asked_plane_;
  UltrasoundImage finished_image_;
  std::thread thread_;
};

}  // namespace fetouch::app::trainer

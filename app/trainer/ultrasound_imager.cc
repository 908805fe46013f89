#include "app/trainer/ultrasound_imager.h"

#include <chrono>
#include <utility>

#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace fetouch::app::trainer {

UltrasoundImager::UltrasoundImager(std::vector<std::array<double, 3>> points,
                                   std::vector<std::array<unsigned int, 4>> tetrahedra, std::vector<unsigned int> material,
                                   std::shared_ptr<const ReferenceVolume> volume, double gain)
    : volume_(std::move(volume)), gain_(gain), slicer_(std::move(points), std::move(tetrahedra), std::move(material)) {
  thread_ = std::thread([this] { run(); });
}

UltrasoundImager::~UltrasoundImager() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void UltrasoundImager::request(long frame, const std::vector<float>& displacement, const SlicePlane& plane) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    asked_frame_ = frame;
    asked_displacement_.assign(displacement.begin(), displacement.end());
    asked_plane_ = plane;
    asked_ = true;
  }
  wake_.notify_one();
}

bool UltrasoundImager::take(UltrasoundImage& image) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!finished_) return false;
  std::swap(image, finished_image_);
  finished_ = false;
  return true;
}

void UltrasoundImager::make_now(long frame, const std::vector<float>& displacement, const SlicePlane& plane,
                                UltrasoundImage& image) {
  std::lock_guard<std::mutex> lock(slicer_mutex_);
  const auto start = std::chrono::steady_clock::now();
  const ReferenceVolume* volume = volume_ && !volume_->empty() ? volume_.get() : nullptr;
  slicer_.slice(displacement, plane, volume, gain_, image.pixels, image.reference);
  image.frame = frame;
  image.plane = plane;
  image.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void UltrasoundImager::run() {
#ifdef __linux__
  // Below the solver: an image late by a tick is not felt, a frame late is.
  setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 5);
#endif
  long frame = -1;
  std::vector<float> displacement;
  SlicePlane plane;
  UltrasoundImage working;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || asked_; });
      if (stop_) return;
      std::swap(displacement, asked_displacement_);
      plane = asked_plane_, frame = asked_frame_;
      asked_ = false;
    }
    make_now(frame, displacement, plane, working);
    std::lock_guard<std::mutex> lock(mutex_);
    std::swap(working, finished_image_);
    finished_ = true;
  }
}

}  // namespace fetouch::app::trainer

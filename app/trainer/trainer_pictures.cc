// The trainer's pictures: ctrl+S and --screenshot (the window with its 3D view), and beside
// --screenshot the ultrasound image and the tissue shown (view_export.h).
#include <QImage>
#include <QPainter>
#include <QPixmap>
#include <QVTKOpenGLStereoWidget.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkImageData.h>
#include <vtkSmartPointer.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>

#include "app/trainer/trainer_window.h"
#include "app/trainer/view_export.h"

namespace fetouch::app::trainer {

void TrainerWindow::export_views(const std::filesystem::path& screenshot) {
  std::filesystem::path stem = screenshot;
  stem.replace_extension();
  try {
    // The image made again from the tissue shown, in the plane shown: the pair is consistent even
    // if the last frame came after the last image.
    UltrasoundImage image;
    imager_->make_now(shown_.frame, shown_.displacement, plane_, image);
    figures_.ultrasound_png = stem.string() + ".ultrasound.png";
    figures_.tissue_vtu = stem.string() + ".vtu";
    write_grey_png(image.pixels, plane_.columns, plane_.rows, figures_.ultrasound_png);
    write_tissue_vtu(session_->mesh(), shown_.displacement, figures_.tissue_vtu);
    figures_.plane = plane_, figures_.gain = gain_, figures_.volume = !volume_->empty(), figures_.frame = shown_.frame;
  } catch (const std::exception& e) {
    figures_.error = e.what();
  }
}

bool TrainerWindow::save_screenshot(const std::filesystem::path& file) {
  std::error_code ignored;
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path(), ignored);
  // The 3D view is a window of its own inside this one, which grab() leaves blank: it is rendered
  // now, read back from VTK's own framebuffer (Qt's may not have been painted yet) and drawn where
  // it shows.
  auto frame = vtkSmartPointer<vtkWindowToImageFilter>::New();
  frame->SetInput(render_window_);
  frame->SetInputBufferTypeToRGB();
  frame->ReadFrontBufferOff();
  frame->ShouldRerenderOn();
  frame->Update();
  vtkImageData* pixels = frame->GetOutput();
  int size[3] = {0, 0, 0};
  pixels->GetDimensions(size);
  QImage view(size[0], size[1], QImage::Format_RGB888);
  const auto* rgb = static_cast<const unsigned char*>(pixels->GetScalarPointer());
  for (int row = 0; rgb && row < size[1]; ++row)  // VTK's rows go up, an image's down
    std::copy_n(rgb + std::size_t(size[1] - 1 - row) * 3 * size[0], 3 * size[0], view.scanLine(row));
  QPixmap picture = grab();
  {
    QPainter painter(&picture);
    painter.drawImage(QRect(vtk_widget_->mapTo(this, QPoint(0, 0)), vtk_widget_->size()), view);
  }
  return picture.save(QString::fromStdString(file.string()));
}

}  // namespace fetouch::app::trainer

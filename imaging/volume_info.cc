#include "imaging/volume_info.h"

#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkDICOMImageReader.h>
#include <vtkImageReader2.h>
#include <vtkMetaImageReader.h>
#include <vtkNew.h>
#include <vtkNrrdReader.h>
#include <vtkSmartPointer.h>
#include <vtkXMLImageDataReader.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkDataObject.h>
#include <vtkDataSetAttributes.h>

#include <stdexcept>
#include <string>

namespace fetouch::imaging {

namespace {

// VTK reports reader failures as error events, not exceptions; collect them so they can be thrown.
struct ErrorCollector {
  std::string messages;
  static void on_error(vtkObject*, unsigned long, void* client, void* call_data) {
    auto* self = static_cast<ErrorCollector*>(client);
    if (call_data) {
      if (!self->messages.empty()) self->messages += "; ";
      std::string text = static_cast<const char*>(call_data);
      while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
      self->messages += text;
    }
  }
};

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

double VolumeInfo::voxel_count() const {
  return double(dimensions[0]) * double(dimensions[1]) * double(dimensions[2]);
}

std::array<double, 3> VolumeInfo::extent_mm() const {
  return {dimensions[0] * spacing_mm[0], dimensions[1] * spacing_mm[1], dimensions[2] * spacing_mm[2]};
}

VolumeInfo read_volume_info(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw std::runtime_error(name + ": no such file");

  VolumeInfo info;
  vtkSmartPointer<vtkAlgorithm> reader;
  if (std::filesystem::is_directory(path, ec)) {
    auto dicom = vtkSmartPointer<vtkDICOMImageReader>::New();
    dicom->SetDirectoryName(name.c_str());
    reader = dicom;
    info.format = "DICOM series";
  } else if (ends_with(name, ".mha") || ends_with(name, ".mhd")) {
    auto meta = vtkSmartPointer<vtkMetaImageReader>::New();
    if (!meta->CanReadFile(name.c_str()))
      throw std::runtime_error(name + ": not a MetaImage file (no readable ObjectType/NDims header)");
    meta->SetFileName(name.c_str());
    reader = meta;
    info.format = "MetaImage";
  } else if (ends_with(name, ".vti")) {
    auto xml = vtkSmartPointer<vtkXMLImageDataReader>::New();
    if (!xml->CanReadFile(name.c_str()))
      throw std::runtime_error(name + ": not a VTK image data (.vti) file");
    xml->SetFileName(name.c_str());
    reader = xml;
    info.format = "VTK image data";
  } else if (ends_with(name, ".nrrd") || ends_with(name, ".nhdr")) {
    auto nrrd = vtkSmartPointer<vtkNrrdReader>::New();
    if (!nrrd->CanReadFile(name.c_str()))
      throw std::runtime_error(name + ": not a NRRD file (missing the NRRD000x magic line)");
    nrrd->SetFileName(name.c_str());
    reader = nrrd;
    info.format = "NRRD";
  } else {
    throw std::runtime_error(name + ": unknown volume format; expected .mha, .mhd, .vti, .nrrd, "
                                    ".nhdr or a folder with a DICOM series");
  }

  ErrorCollector errors;
  vtkNew<vtkCallbackCommand> callback;
  callback->SetCallback(&ErrorCollector::on_error);
  callback->SetClientData(&errors);
  reader->AddObserver(vtkCommand::ErrorEvent, callback);
  reader->UpdateInformation();
  if (!errors.messages.empty()) throw std::runtime_error(name + ": " + errors.messages);

  vtkInformation* out = reader->GetOutputInformation(0);
  int whole[6] = {0, -1, 0, -1, 0, -1};
  out->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), whole);
  for (int i = 0; i < 3; ++i) info.dimensions[i] = whole[2 * i + 1] - whole[2 * i] + 1;
  if (out->Has(vtkDataObject::SPACING())) {
    double spacing[3];
    out->Get(vtkDataObject::SPACING(), spacing);
    for (int i = 0; i < 3; ++i) info.spacing_mm[i] = spacing[i];
  }
  if (out->Has(vtkDataObject::ORIGIN())) {
    double origin[3];
    out->Get(vtkDataObject::ORIGIN(), origin);
    for (int i = 0; i < 3; ++i) info.origin_mm[i] = origin[i];
  }
  vtkInformation* scalars = vtkDataObject::GetActiveFieldInformation(
      out, vtkDataObject::FIELD_ASSOCIATION_POINTS, vtkDataSetAttributes::SCALARS);
  if (scalars) {
    info.components = scalars->Has(vtkDataObject::FIELD_NUMBER_OF_COMPONENTS())
                          ? scalars->Get(vtkDataObject::FIELD_NUMBER_OF_COMPONENTS())
                          : 1;
    if (scalars->Has(vtkDataObject::FIELD_ARRAY_TYPE()))
      info.scalar_type = vtkImageScalarTypeNameMacro(scalars->Get(vtkDataObject::FIELD_ARRAY_TYPE()));
  }
  if (info.dimensions[0] <= 0 || info.dimensions[1] <= 0 || info.dimensions[2] <= 0)
    throw std::runtime_error(name + ": the header gives no voxels (empty extent)");
  return info;
}

}  // namespace fetouch::imaging

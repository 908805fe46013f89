#include "imaging/volume_io.h"

#include "imaging/nifti_io.h"
#include "imaging/volume_header.h"
#include "imaging/volume_info.h"
#include "imaging/vtk_message.h"

#include <vtkAlgorithm.h>
#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkDICOMImageReader.h>
#include <vtkDataSetAttributes.h>
#include <vtkInformation.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkMetaImageReader.h>
#include <vtkMetaImageWriter.h>
#include <vtkNrrdReader.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLImageDataWriter.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vtkNew.h>
#include <cctype>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

namespace fetouch::imaging {

namespace {

std::string extension(const std::filesystem::path& path) {
  std::string e = path.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

// VTK's own messages off while it lives (the errors thrown here say what is wrong).
class QuietVtk {
 public:
  QuietVtk() : previous_(vtkObject::GetGlobalWarningDisplay()) { vtkObject::GlobalWarningDisplayOff(); }
  ~QuietVtk() { vtkObject::SetGlobalWarningDisplay(previous_); }
  QuietVtk(const QuietVtk&) = delete;
  QuietVtk& operator=(const QuietVtk&) = delete;

 private:
  int previous_;
};

vtkImageData* run(vtkAlgorithm* reader) {
  const QuietVtk quiet;
  reader->Update();
  return vtkImageData::SafeDownCast(reader->GetOutputDataObject(0));
}

// VTK reports reader failures as error events, not exceptions: this collects a reader's, to throw.
// It registers its own address with the reader, so it stays where it is made.
class ReaderErrors {
 public:
  explicit ReaderErrors(vtkAlgorithm* reader) {
    callback_->SetCallback(&ReaderErrors::on_error);
    callback_->SetClientData(this);
    reader->AddObserver(vtkCommand::ErrorEvent, callback_);
  }
  ReaderErrors(const ReaderErrors&) = delete;
  ReaderErrors& operator=(const ReaderErrors&) = delete;
  const std::string& messages() const { return messages_; }

 private:
  static void on_error(vtkObject*, unsigned long, void* client, void* call_data) {
    auto* self = static_cast<ReaderErrors*>(client);
    if (!call_data) return;
    const std::string text = vtk_message(static_cast<const char*>(call_data));
    if (self->messages_.size() < 300) self->messages_ += (self->messages_.empty() ? "" : "; ") + text;
  }
  std::string messages_;
  vtkNew<vtkCallbackCommand> callback_;
};

struct OpenVolume {
  vtkSmartPointer<vtkAlgorithm> reader;
  std::string format;
  std::unique_ptr<ReaderErrors> errors;
};

// The reader for a file (by extension) or a folder (a DICOM series), its header read.
std::unique_ptr<OpenVolume> open_volume(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw std::runtime_error(name + ": no such file");
  if (!std::filesystem::is_regular_file(path, ec))
    throw std::runtime_error(name + ": not a regular file (a volume is a file or a folder of DICOM slices, not a FIFO or device)");
  auto v = std::make_unique<OpenVolume>();
  const std::string e = extension(path);
  if (e == ".mha" || e == ".mhd") {
    // Checked before VTK looks at it at all: CanReadFile already runs MetaIO's header parser.
    check_metaimage_size(path);
    auto r = vtkSmartPointer<vtkMetaImageReader>::New();
    if (!r->CanReadFile(name.c_str()))
      throw std::runtime_error(name + ": not a MetaImage file (no readable ObjectType/NDims header)");
    r->SetFileName(name.c_str());
    v->reader = r, v->format = "MetaImage";
  } else if (e == ".vti") {
    {
      // A VTK file has no document type: entity declarations only serve to expand (the billion laughs).
      std::ifstream head(path, std::ios::binary);
      std::string text(65536, '\0');
      head.read(text.data(), static_cast<std::streamsize>(text.size()));
      text.resize(static_cast<std::size_t>(head.gcount()));
      if (text.find("<!DOCTYPE") != std::string::npos || text.find("<!ENTITY") != std::string::npos)
        throw std::runtime_error(name + ": an XML document type or entity declaration; a VTK file has none");
    }
    auto r = vtkSmartPointer<vtkXMLImageDataReader>::New();
    if (!r->CanReadFile(name.c_str())) throw std::runtime_error(name + ": not a VTK image data (.vti) file");
    r->SetFileName(name.c_str());
    v->reader = r, v->format = "VTK image data";
  } else if (e == ".nrrd" || e == ".nhdr") {
    auto r = vtkSmartPointer<vtkNrrdReader>::New();
    if (!r->CanReadFile(name.c_str())) throw std::runtime_error(name + ": not a NRRD file (missing the NRRD000x magic line)");
    check_nrrd_size(path);
    r->SetFileName(name.c_str());
    v->reader = r, v->format = "NRRD";
  } else {
    throw std::runtime_error(name + ": unknown volume format '" + e +
                             "'; expected .mha, .mhd, .vti, .nrrd, .nhdr, .nii, .nii.gz, .hdr or a folder with a DICOM series");
  }
  v->errors = std::make_unique<ReaderErrors>(v->reader);
  {
    const QuietVtk quiet;
    v->reader->UpdateInformation();
  }
  if (!v->errors->messages().empty()) throw std::runtime_error(name + ": " + v->errors->messages());
  return v;
}

std::vector<double> numbers(std::string text) {
  for (char& c : text)
    if (c == '(' || c == ')' || c == ',' || c == '\\') c = ' ';
  std::istringstream in(text);
  std::vector<double> out;
  for (double x; in >> x;) out.push_back(x);
  return out;
}

// Spacing, origin and direction (column c: index axis c) from what each format says.
void read_geometry(const std::filesystem::path& path, OpenVolume& v, VolumeInfo& info) {
  const std::string name = path.string();
  vtkInformation* out = v.reader->GetOutputInformation(0);
  double spacing[3] = {1, 1, 1}, origin[3] = {0, 0, 0};
  if (out->Has(vtkDataObject::SPACING())) out->Get(vtkDataObject::SPACING(), spacing);
  if (out->Has(vtkDataObject::ORIGIN())) out->Get(vtkDataObject::ORIGIN(), origin);
  for (int d = 0; d < 3; ++d) info.spacing_mm[d] = spacing[d], info.origin_mm[d] = origin[d];
  info.direction = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const auto set_columns = [&](const std::vector<double>& axes, const std::string& what) {
    // axes: three vectors, one per index axis, each normalised here.
    for (int c = 0; c < 3; ++c) {
      const double n = std::sqrt(axes[3 * c] * axes[3 * c] + axes[3 * c + 1] * axes[3 * c + 1] + axes[3 * c + 2] * axes[3 * c + 2]);
      if (!(n > 0)) throw std::runtime_error(name + ": " + what + " has a zero axis");
      for (int r = 0; r < 3; ++r) info.direction[3 * r + c] = axes[3 * c + r] / n;
    }
  };
  if (info.format == "MetaImage") {
    // TransformMatrix (also called Rotation or Orientation): the direction of index axis 0, then
    // of axis 1, then of axis 2 (the order ITK writes).
    auto keys = text_header(path, '=');
    for (const char* key : {"TransformMatrix", "Rotation", "Orientation"})
      if (keys.count(key)) {
        const auto m = numbers(keys[key]);
        if (m.size() != 9) throw std::runtime_error(name + ": " + key + " needs 9 numbers, not '" + keys[key] + "'");
        set_columns(m, key);
        break;
      }
  } else if (info.format == "NRRD") {
    // "space directions: (x,y,z) (x,y,z) (x,y,z)": each index axis' step in space (mm), so both
    // the direction and the spacing; "space origin: (x,y,z)".
    auto keys = text_header(path, ':');
    if (keys.count("space directions")) {
      const auto m = numbers(keys["space directions"]);
      if (m.size() != 9) throw std::runtime_error(name + ": 'space directions' needs three 3-vectors, not '" + keys["space directions"] + "'");
      for (int c = 0; c < 3; ++c) info.spacing_mm[c] = std::sqrt(m[3 * c] * m[3 * c] + m[3 * c + 1] * m[3 * c + 1] + m[3 * c + 2] * m[3 * c + 2]);
      set_columns(m, "'space directions'");
    }
    if (keys.count("space origin")) {
      const auto o = numbers(keys["space origin"]);
      if (o.size() != 3) throw std::runtime_error(name + ": 'space origin' needs a 3-vector, not '" + keys["space origin"] + "'");
      for (int d = 0; d < 3; ++d) info.origin_mm[d] = o[d];
    }
  } else if (info.format == "VTK image data") {
    if (out->Has(vtkDataObject::DIRECTION())) out->Get(vtkDataObject::DIRECTION(), info.direction.data());
  }
}

// A DICOM series: a folder of single-frame files, one slice each. VTK's series reader takes
// PixelSpacing's two values in the wrong order (DICOM lists the spacing between rows first), turns
// images upside down and orders slices its own way, so the files are read one by one and stacked
// here along the slices' normal, by their Image Position (Patient).
Volume<float> read_dicom_series(const std::filesystem::path& folder) {
  const std::string name = folder.string();
  struct Slice {
    std::filesystem::path file;
    double along = 0;
    std::array<double, 3> position{};
    vtkSmartPointer<vtkImageData> image;
  };
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder))
    if (entry.is_regular_file()) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  std::vector<Slice> slices;
  std::array<double, 6> orientation{};
  std::array<double, 2> pixel_spacing{};  // between rows, between columns
  int size[2] = {0, 0};
  for (const auto& file : files) {
    auto r = vtkSmartPointer<vtkDICOMImageReader>::New();
    if (!r->CanReadFile(file.string().c_str())) continue;  // not DICOM (a DICOMDIR, notes, ...)
    r->SetFileName(file.string().c_str());
    const ReaderErrors errors(r);
    vtkImageData* image = run(r);
    if (!errors.messages().empty() || !image || !image->GetPointData()->GetScalars())
      throw std::runtime_error(file.string() + ": no image could be read" + (errors.messages().empty() ? "" : ": " + errors.messages()));
    int dims[3];
    image->GetDimensions(dims);
    const float* iop = r->GetImageOrientationPatient();
    const float* ipp = r->GetImagePositionPatient();
    const double* ps = r->GetPixelSpacing();
    if (dims[2] != 1) throw std::runtime_error(file.string() + ": multi-frame images are not read (one slice per file)");
    if (slices.empty()) {
      size[0] = dims[0], size[1] = dims[1];
      for (int k = 0; k < 6; ++k) orientation[k] = iop[k];
      pixel_spacing = {ps[0], ps[1]};
    } else {
      bool same = size[0] == dims[0] && size[1] == dims[1];
      for (int k = 0; k < 6; ++k) same = same && std::abs(orientation[k] - iop[k]) < 1e-4;
      if (!same)
        throw std::runtime_error(file.string() + ": its size or orientation differs from " + slices[0].file.string() +
                                 "'s (one series per folder)");
    }
    Slice slice;
    slice.file = file;
    slice.position = {ipp[0], ipp[1], ipp[2]};
    slice.image = image;
    slices.push_back(slice);
  }
  if (slices.empty()) throw std::runtime_error(name + ": no DICOM file in this folder");
  const double row[3] = {orientation[0], orientation[1], orientation[2]};
  const double column[3] = {orientation[3], orientation[4], orientation[5]};
  const double normal[3] = {row[1] * column[2] - row[2] * column[1], row[2] * column[0] - row[0] * column[2],
                            row[0] * column[1] - row[1] * column[0]};
  const double n = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
  if (std::abs(n - 1) > 1e-3)
    throw std::runtime_error(name + ": Image Orientation (Patient) is not two unit, orthogonal directions");
  for (auto& slice : slices)
    slice.along = slice.position[0] * normal[0] + slice.position[1] * normal[1] + slice.position[2] * normal[2];
  std::sort(slices.begin(), slices.end(), [](const Slice& a, const Slice& b) { return a.along < b.along; });
  double step = 1;
  if (slices.size() > 1) {
    step = (slices.back().along - slices.front().along) / double(slices.size() - 1);
    for (std::size_t k = 1; k < slices.size(); ++k)
      if (!(std::abs(slices[k].along - slices[k - 1].along - step) <= 0.01 * std::abs(step)) || !(step > 0))
        throw std::runtime_error(name + ": slices " + slices[k - 1].file.filename().string() + " and " +
                                 slices[k].file.filename().string() + " are " +
                                 std::to_string(slices[k].along - slices[k - 1].along) + " mm apart, the series " +
                                 std::to_string(step) + " mm on average (uneven or repeated slices)");
  }
  Volume<float> v;
  v.dimensions = {size[0], size[1], static_cast<int>(slices.size())};
  v.spacing_mm = {pixel_spacing[1], pixel_spacing[0], step};
  v.origin_mm = slices[0].position;
  v.direction = {row[0], column[0], normal[0], row[1], column[1], normal[1], row[2], column[2], normal[2]};
  v.data.resize(std::size_t(size[0]) * size[1] * slices.size());
  for (std::size_t k = 0; k < slices.size(); ++k) {
    vtkDataArray* scalars = slices[k].image->GetPointData()->GetScalars();
    for (int j = 0; j < size[1]; ++j)      // row j of the image ...
      for (int i = 0; i < size[0]; ++i)  // ... is VTK's row size - 1 - j
        v.data[v.index(i, j, static_cast<int>(k))] =
            static_cast<float>(scalars->GetComponent(vtkIdType(size[1] - 1 - j) * size[0] + i, 0));
  }
  return v;
}

// What a clinical image can be, whatever its format said (issue 17): voxels of 1 um to 100 mm, an
// origin within 100 m, axes that span 3D, at most 2^30 voxels (4 GB as floats).
void check_plausible(const std::filesystem::path& path, const VolumeInfo& info) {
  const std::string name = path.string();
  const auto triple = [](const std::array<double, 3>& v) {
    std::ostringstream text;
    text << v[0] << " " << v[1] << " " << v[2];
    return text.str();
  };
  for (double s : info.spacing_mm)
    if (!(s >= 1e-3 && s <= 100))
      throw std::runtime_error(name + ": voxel size " + triple(info.spacing_mm) + " mm; each must be 0.001 to 100 mm");
  for (double o : info.origin_mm)
    if (!(std::abs(o) <= 1e5)) throw std::runtime_error(name + ": origin " + triple(info.origin_mm) + " mm; expected within 100 m");
  const auto& d = info.direction;
  const double det = d[0] * (d[4] * d[8] - d[5] * d[7]) - d[1] * (d[3] * d[8] - d[5] * d[6]) + d[2] * (d[3] * d[7] - d[4] * d[6]);
  if (!(std::abs(det) > 0.5))
    throw std::runtime_error(name + ": its direction (orientation) matrix has determinant " + std::to_string(det) +
                             "; the image axes must span 3D space");
  if (info.voxel_count() > double(1u << 30))
    throw std::runtime_error(name + ": " + std::to_string(info.dimensions[0]) + " x " + std::to_string(info.dimensions[1]) + " x " +
                             std::to_string(info.dimensions[2]) + " voxels; at most 2^30 fit the memory budget (4 GB as floats)");
}

VolumeInfo info_of(const std::filesystem::path& path, OpenVolume& v) {
  VolumeInfo info;
  info.format = v.format;
  vtkInformation* out = v.reader->GetOutputInformation(0);
  int whole[6] = {0, -1, 0, -1, 0, -1};
  out->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), whole);
  for (int i = 0; i < 3; ++i) info.dimensions[i] = whole[2 * i + 1] - whole[2 * i] + 1;
  if (info.dimensions[0] <= 0 || info.dimensions[1] <= 0 || info.dimensions[2] <= 0)
    throw std::runtime_error(path.string() + ": the header gives no voxels (empty extent)");
  vtkInformation* scalars = vtkDataObject::GetActiveFieldInformation(out, vtkDataObject::FIELD_ASSOCIATION_POINTS,
                                                                      vtkDataSetAttributes::SCALARS);
  if (scalars) {
    info.components = scalars->Has(vtkDataObject::FIELD_NUMBER_OF_COMPONENTS())
                           ? scalars->Get(vtkDataObject::FIELD_NUMBER_OF_COMPONENTS())
                           : 1;
    if (scalars->Has(vtkDataObject::FIELD_ARRAY_TYPE()))
      info.scalar_type = vtkImageScalarTypeNameMacro(scalars->Get(vtkDataObject::FIELD_ARRAY_TYPE()));
  }
  read_geometry(path, v, info);
  check_plausible(path, info);
  return info;
}

}  // namespace

double VolumeInfo::voxel_count() const { return double(dimensions[0]) * double(dimensions[1]) * double(dimensions[2]); }

std::array<double, 3> VolumeInfo::extent_mm() const {
  return {dimensions[0] * spacing_mm[0], dimensions[1] * spacing_mm[1], dimensions[2] * spacing_mm[2]};
}

VolumeInfo read_volume_info(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    const Volume<float> series = read_dicom_series(path);
    VolumeInfo info;
    info.format = "DICOM series";
    info.dimensions = series.dimensions, info.spacing_mm = series.spacing_mm, info.origin_mm = series.origin_mm;
    info.direction = series.direction, info.components = 1, info.scalar_type = "float";
    return info;
  }
  if (is_nifti_name(path)) {
    const VolumeInfo info = read_nifti_info(path);
    check_plausible(path, info);
    return info;
  }
  auto v = open_volume(path);
  return info_of(path, *v);
}

Volume<float> read_volume(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return read_dicom_series(path);
  if (is_nifti_name(path)) {
    check_plausible(path, read_nifti_info(path));
    return read_nifti(path);
  }
  auto opened = open_volume(path);
  const VolumeInfo info = info_of(path, *opened);
  vtkImageData* image = run(opened->reader);
  if (!opened->errors->messages().empty()) throw std::runtime_error(name + ": " + opened->errors->messages());
  int dims[3] = {0, 0, 0};
  if (image) image->GetDimensions(dims);
  vtkDataArray* scalars = image ? image->GetPointData()->GetScalars() : nullptr;
  const double expected = double(dims[0]) * dims[1] * dims[2];
  if (!scalars || expected <= 0) throw std::runtime_error(name + ": no voxels could be read (truncated or empty data?)");
  if (double(scalars->GetNumberOfTuples()) != expected)
    throw std::runtime_error(name + ": the dimensions say " + std::to_string(static_cast<long long>(expected)) +
                             " voxels but the data holds " + std::to_string(scalars->GetNumberOfTuples()));
  Volume<float> v;
  for (int d = 0; d < 3; ++d) v.dimensions[d] = dims[d];
  v.spacing_mm = info.spacing_mm, v.origin_mm = info.origin_mm, v.direction = info.direction;
  v.data.resize(static_cast<std::size_t>(expected));
  for (vtkIdType i = 0; i < scalars->GetNumberOfTuples(); ++i) {
    v.data[i] = static_cast<float>(scalars->GetComponent(i, 0));
    if (!std::isfinite(v.data[i]))
      throw std::runtime_error(name + ": voxel (" + std::to_string(i % dims[0]) + ", " + std::to_string(i / dims[0] % dims[1]) + ", " +
                               std::to_string(i / (vtkIdType(dims[0]) * dims[1])) + ") is " + (std::isnan(v.data[i]) ? "NaN" : "infinite") +
                               "; an image's intensities are finite");
  }
  return v;
}

void write_volume(const Volume<std::uint8_t>& volume, const std::filesystem::path& path) {
  const std::string name = path.string();
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(volume.dimensions.data());
  image->SetSpacing(volume.spacing_mm.data());
  image->SetOrigin(volume.origin_mm.data());
  image->SetDirectionMatrix(volume.direction.data());
  auto data = vtkSmartPointer<vtkUnsignedCharArray>::New();
  data->SetName("intensity");
  data->SetNumberOfTuples(static_cast<vtkIdType>(volume.data.size()));
  std::copy(volume.data.begin(), volume.data.end(), data->GetPointer(0));
  image->GetPointData()->SetScalars(data);
  const std::string e = extension(path);
  if (e != ".mha" && e != ".mhd" && e != ".vti")
    throw std::runtime_error(name + ": volumes are written as .mha, .mhd or .vti");
  int ok = 0;
  {
    const QuietVtk quiet;
    if (e == ".vti") {
      auto w = vtkSmartPointer<vtkXMLImageDataWriter>::New();
      w->SetFileName(name.c_str());
      w->SetInputData(image);
      ok = w->Write();
    } else {
      auto w = vtkSmartPointer<vtkMetaImageWriter>::New();
      w->SetFileName(name.c_str());
      w->SetCompression(true);
      w->SetInputData(image);
      w->Write();
      ok = w->GetErrorCode() == 0;
    }
  }
  if (!ok || !std::filesystem::exists(path)) throw std::runtime_error(name + ": could not be written");
  if (e != ".vti" && volume.direction != std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1}) {
    // VTK's MetaImage writer always writes an identity TransformMatrix: the header line is
    // replaced (axis 0's direction, then axis 1's, then axis 2's, as ITK writes it).
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    const auto at = bytes.find("TransformMatrix = ");
    const auto end = at == std::string::npos ? at : bytes.find('\n', at);
    if (end == std::string::npos) throw std::runtime_error(name + ": no TransformMatrix line to write the orientation in");
    std::ostringstream line;
    line.precision(17);
    line << "TransformMatrix =";
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) line << ' ' << volume.direction[3 * r + c];
    bytes.replace(at, end - at, line.str());
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << bytes;
    if (!out) throw std::runtime_error(name + ": could not be written");
  }
}

}  // namespace fetouch::imaging

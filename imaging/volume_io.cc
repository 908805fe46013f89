#include "imaging/volume_io.h"

#include <vtkAlgorithm.h>
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
#include <cctype>
#include <fstream>
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

// MetaImage: VTK's reader fills a short file's missing voxels with whatever it finds, so the data
// size is checked against the header first (uncompressed data; compressed data is checked by zlib).
void check_metaimage_size(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::map<std::string, std::string> keys;
  std::string line;
  std::streamoff header = 0;
  while (std::getline(in, line)) {
    header = in.tellg();
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    auto trim = [](std::string t) {
      t.erase(0, t.find_first_not_of(" \t\r"));
      t.erase(t.find_last_not_of(" \t\r") + 1);
      return t;
    };
    const std::string key = trim(line.substr(0, eq)), value = trim(line.substr(eq + 1));
    keys[key] = value;
    if (key == "ElementDataFile") break;  // the last header line
  }
  const auto get = [&](const std::string& key) { return keys.count(key) ? keys[key] : std::string(); };
  const std::string compressed = get("CompressedData");
  if (compressed == "True" || compressed == "true") return;
  std::istringstream dims(get("DimSize"));
  double voxels = 1;
  int n = 0;
  for (double d; dims >> d; ++n) voxels *= d;
  if (n == 0) throw std::runtime_error(path.string() + ": the header has no DimSize");
  static const std::map<std::string, int> bytes{{"MET_UCHAR", 1}, {"MET_CHAR", 1},   {"MET_USHORT", 2}, {"MET_SHORT", 2},
                                                {"MET_UINT", 4},  {"MET_INT", 4},    {"MET_FLOAT", 4},  {"MET_DOUBLE", 8},
                                                {"MET_ULONG", 8}, {"MET_LONG", 8}};
  const auto type = bytes.find(get("ElementType"));
  if (type == bytes.end()) throw std::runtime_error(path.string() + ": unknown ElementType '" + get("ElementType") + "'");
  const std::string channels = get("ElementNumberOfChannels");
  const double expected = voxels * type->second * (channels.empty() ? 1 : std::stod(channels));
  const std::string data = get("ElementDataFile");
  double available = 0;
  if (data == "LOCAL") {
    available = double(std::filesystem::file_size(path)) - double(header);
  } else {
    const auto file = path.parent_path() / data;
    if (!std::filesystem::is_regular_file(file))
      throw std::runtime_error(path.string() + ": its data file " + file.string() + " is missing");
    available = double(std::filesystem::file_size(file));
  }
  if (available < expected)
    throw std::runtime_error(path.string() + ": DimSize " + get("DimSize") + " of " + get("ElementType") + " needs " +
                             std::to_string(static_cast<long long>(expected)) + " bytes but the file holds " +
                             std::to_string(static_cast<long long>(available)));
}

}  // namespace

Volume<float> read_volume(const std::filesystem::path& path) {
  const std::string name = path.string();
  if (!std::filesystem::is_regular_file(path)) throw std::runtime_error(name + ": no such file");
  const std::string e = extension(path);
  vtkSmartPointer<vtkAlgorithm> reader;
  if (e == ".mha" || e == ".mhd") {
    auto r = vtkSmartPointer<vtkMetaImageReader>::New();
    if (!r->CanReadFile(name.c_str())) throw std::runtime_error(name + ": not a MetaImage file (bad header)");
    check_metaimage_size(path);
    r->SetFileName(name.c_str());
    reader = r;
  } else if (e == ".vti") {
    auto r = vtkSmartPointer<vtkXMLImageDataReader>::New();
    if (!r->CanReadFile(name.c_str())) throw std::runtime_error(name + ": not a VTK image data file");
    r->SetFileName(name.c_str());
    reader = r;
  } else if (e == ".nrrd" || e == ".nhdr") {
    auto r = vtkSmartPointer<vtkNrrdReader>::New();
    if (!r->CanReadFile(name.c_str())) throw std::runtime_error(name + ": not a NRRD file (bad header)");
    r->SetFileName(name.c_str());
    reader = r;
  } else {
    throw std::runtime_error(name + ": unknown volume format '" + e + "' (.mha, .mhd, .vti, .nrrd, .nhdr)");
  }
  vtkImageData* image = run(reader);
  int dims[3] = {0, 0, 0};
  if (image) image->GetDimensions(dims);
  vtkDataArray* scalars = image ? image->GetPointData()->GetScalars() : nullptr;
  const double expected = double(dims[0]) * dims[1] * dims[2];
  if (!scalars || expected <= 0) throw std::runtime_error(name + ": no voxels could be read (truncated or empty data?)");
  if (double(scalars->GetNumberOfTuples()) != expected)
    throw std::runtime_error(name + ": the dimensions say " + std::to_string(static_cast<long long>(expected)) +
                             " voxels but the data holds " + std::to_string(scalars->GetNumberOfTuples()));
  Volume<float> v;
  double spacing[3], origin[3];
  image->GetSpacing(spacing);
  image->GetOrigin(origin);
  for (int d = 0; d < 3; ++d) v.dimensions[d] = dims[d], v.spacing_mm[d] = spacing[d], v.origin_mm[d] = origin[d];
  v.data.resize(static_cast<std::size_t>(expected));
  for (vtkIdType i = 0; i < scalars->GetNumberOfTuples(); ++i) v.data[i] = static_cast<float>(scalars->GetComponent(i, 0));
  return v;
}

void write_volume(const Volume<std::uint8_t>& volume, const std::filesystem::path& path) {
  const std::string name = path.string();
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(volume.dimensions.data());
  image->SetSpacing(volume.spacing_mm.data());
  image->SetOrigin(volume.origin_mm.data());
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
}

}  // namespace fetouch::imaging

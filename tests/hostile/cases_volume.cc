// Volumes: `fetouch mesh VOLUME` on broken MetaImage, NRRD and VTK image files, and `reconstruct` on
// broken tracked sweeps.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>

#include "tests/hostile/hostile_case.h"

namespace fetouch::testing::hostile {

namespace {

constexpr int kN = 16;  // a 16^3 volume of 1 mm voxels: a bright ball in a dark background

std::string ball_voxels() {
  std::string v(kN * kN * kN, '\x14');
  for (int k = 0; k < kN; ++k)
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i)
        if (std::hypot(i - 7.5, j - 7.5, k - 7.5) < 5.5) v[static_cast<std::size_t>((k * kN + j) * kN + i)] = '\xc8';
  return v;
}

// A MetaImage header; `change` replaces one of its lines' text.
std::string mha_header(const std::string& data_file = "LOCAL") {
  return "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nDimSize = 16 16 16\n"
         "ElementSpacing = 1 1 1\nOffset = 0 0 0\nElementType = MET_UCHAR\nElementDataFile = " + data_file + "\n";
}

std::string mha(const std::string& from = "", const std::string& to = "", const std::string& voxels = ball_voxels()) {
  std::string header = mha_header();
  if (!from.empty()) header = replaced(header, from, to);
  return header + voxels;
}

Invocation mesh_volume(const std::string& volume, int exit_code = 2) {
  return {{"mesh", volume, "--out", "out/tissue.vtu"}, volume, exit_code};
}

Case volume(const std::string& name, const std::string& guards, const std::string& form, const std::string& file,
            const std::function<std::string()>& bytes, int exit_code = 2) {
  return {name, "volume", guards, form, [=](const fs::path& dir) {
            write_text(dir / file, bytes());
            return mesh_volume(file, exit_code);
          }};
}

Case header_edit(const std::string& name, const std::string& guards, const std::string& form, const std::string& from,
                 const std::string& to) {
  return volume(name, guards, form, "tissue.mha", [=] { return mha(from, to); });
}

std::string nrrd(const std::string& from = "", const std::string& to = "") {
  std::string header = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 16 16 16\nspacings: 1 1 1\nencoding: raw\nendian: little\n\n";
  if (!from.empty()) header = replaced(header, from, to);
  return header + ball_voxels();
}

// A tracked sweep of three 8 x 8 frames 1 mm apart, as PLUS writes them, and its calibration.
std::string sweep(const std::string& from = "", const std::string& to = "") {
  std::string t = "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nDimSize = 8 8 3\n"
                  "ElementSpacing = 1 1 1\nElementType = MET_UCHAR\nUltrasoundImageOrientation = MF\n";
  for (int f = 0; f < 3; ++f) {
    char prefix[32];
    std::snprintf(prefix, sizeof prefix, "Seq_Frame%04d_", f);
    t += std::string(prefix) + "ProbeToTrackerTransform = 1 0 0 0 0 1 0 0 0 0 1 " + std::to_string(f) + " 0 0 0 1\n";
    t += std::string(prefix) + "ProbeToTrackerTransformStatus = OK\n";
    t += std::string(prefix) + "ReferenceToTrackerTransform = 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n";
    t += std::string(prefix) + "ReferenceToTrackerTransformStatus = OK\n";
  }
  t += "ElementDataFile = LOCAL\n";
  if (!from.empty()) t = replaced(t, from, to);
  return t + std::string(8 * 8 * 3, '\x80');
}

}  // namespace

std::string calibration_text() {
  return "<PlusConfiguration version=\"2.1\">\n  <CoordinateDefinitions>\n"
         "    <Transform From=\"Image\" To=\"Probe\"\n      Matrix=\"0.1 0 0 0  0 0.1 0 0  0 0 0.1 0  0 0 0 1\" />\n"
         "  </CoordinateDefinitions>\n</PlusConfiguration>\n";
}

std::string sweep_text() { return sweep(); }

std::vector<Case> volume_cases() {
  std::vector<Case> c;
  c.push_back(volume("ValidMetaImage", "valid", "name", "tissue.mha", [] { return mha(); }, 0));
  c.push_back(volume("ValidNrrdUnicodeName", "valid", "name", "объём_体积.nrrd", [] { return nrrd(); }, 0));
  // Geometry that is not a clinical image's.
  c.push_back(header_edit("NegativeSpacing", "nonsense", "absurd", "ElementSpacing = 1 1 1", "ElementSpacing = 1 -1 1"));
  c.push_back(header_edit("ZeroSpacing", "nonsense", "absurd", "ElementSpacing = 1 1 1", "ElementSpacing = 1 0 1"));
  c.push_back(header_edit("NaNSpacing", "nonsense", "non-finite", "ElementSpacing = 1 1 1", "ElementSpacing = 1 nan 1"));
  c.push_back(header_edit("InfiniteSpacing", "nonsense", "non-finite", "ElementSpacing = 1 1 1", "ElementSpacing = 1 inf 1"));
  c.push_back(header_edit("SpacingOfAKilometre", "nonsense", "absurd", "ElementSpacing = 1 1 1", "ElementSpacing = 1e6 1e6 1e6"));
  c.push_back(header_edit("SpacingOfANanometre", "nonsense", "absurd", "ElementSpacing = 1 1 1", "ElementSpacing = 1e-6 1e-6 1e-6"));
  c.push_back(header_edit("NaNOrigin", "nonsense", "non-finite", "Offset = 0 0 0", "Offset = 0 nan 0"));
  c.push_back(header_edit("OriginBeyondTheSun", "nonsense", "absurd", "Offset = 0 0 0", "Offset = 1e300 0 0"));
  c.push_back(header_edit("SingularDirection", "nonsense", "absurd", "Offset = 0 0 0", "Offset = 0 0 0\nTransformMatrix = 1 0 0 1 0 0 0 0 1"));
  c.push_back(volume("ConstantVolume", "nonsense", "absurd", "tissue.mha", [] { return mha("", "", std::string(kN * kN * kN, '\x50')); }));
  c.push_back(volume("AllNaNFloats", "nonsense", "non-finite", "tissue.mha", [] {
    const float nan = std::nanf("");
    std::string v(kN * kN * kN * sizeof(float), '\0');
    for (std::size_t i = 0; i < v.size() / sizeof(float); ++i) std::memcpy(&v[i * sizeof(float)], &nan, sizeof nan);
    return mha("ElementType = MET_UCHAR", "ElementType = MET_FLOAT", v);
  }));
  c.push_back(volume("InfiniteFloats", "nonsense", "non-finite", "tissue.mha", [] {
    std::string v(kN * kN * kN * sizeof(float), '\0');
    const std::string ball = ball_voxels();
    for (std::size_t i = 0; i < ball.size(); ++i) {
      const float x = ball[i] == '\xc8' ? INFINITY : 20.0f;
      std::memcpy(&v[i * sizeof(float)], &x, sizeof x);
    }
    return mha("ElementType = MET_UCHAR", "ElementType = MET_FLOAT", v);
  }));
  // Sizes.
  c.push_back(header_edit("DimSizeZero", "unclear", "wrong shape", "DimSize = 16 16 16", "DimSize = 16 0 16"));
  c.push_back(header_edit("DimSizeNegative", "crash", "wrong shape", "DimSize = 16 16 16", "DimSize = 16 -16 16"));
  c.push_back(header_edit("DimSizeWords", "unclear", "wrong shape", "DimSize = 16 16 16", "DimSize = sixteen 16 16"));
  c.push_back(header_edit("DimSizeOfATrillionVoxels", "hang", "huge", "DimSize = 16 16 16", "DimSize = 10000 10000 10000"));
  c.push_back(header_edit("TwoDimensions", "unclear", "wrong shape", "NDims = 3\n", "NDims = 2\n"));
  c.push_back(header_edit("FourDimensions", "unclear", "wrong shape", "NDims = 3\n", "NDims = 4\n"));
  c.push_back(header_edit("UnknownElementType", "unclear", "wrong shape", "MET_UCHAR", "MET_QUATERNION"));
  c.push_back(header_edit("ChannelsAsWord", "unclear", "wrong shape", "ElementType = MET_UCHAR", "ElementNumberOfChannels = many\nElementType = MET_UCHAR"));
  c.push_back(header_edit("ChannelsAMillion", "hang", "huge", "ElementType = MET_UCHAR", "ElementNumberOfChannels = 1000000\nElementType = MET_UCHAR"));
  c.push_back(volume("DataCutShort", "crash", "truncated", "tissue.mha", [] { return mha("", "", ball_voxels().substr(0, 1000)); }));
  c.push_back(volume("HeaderOnly", "crash", "truncated", "tissue.mha", [] { return mha_header(); }));
  c.push_back(volume("HeaderCutShort", "unclear", "truncated", "tissue.mha", [] { return mha_header().substr(0, 40); }));
  c.push_back(header_edit("CompressedGarbage", "crash", "malformed", "BinaryData = True", "BinaryData = True\nCompressedData = True"));
  c.push_back(volume("EmptyVolume", "unclear", "truncated", "tissue.mha", [] { return std::string(); }));
  c.push_back(volume("GarbageVolume", "unclear", "malformed", "tissue.mha", [] { return garbage(4096, 9); }));
  c.push_back(volume("HeaderLineOfAMegabyte", "hang", "huge", "tissue.mha", [] { return "ObjectType = " + std::string(1u << 20, 'I') + "\n" + mha(); }));
  // MetaIO reads a line without '=' as a key whose value is the next line, so ElementDataFile is
  // lost and the voxels are read as keys; a key of over 254 characters overflows its field name.
  c.push_back(header_edit("LineWithoutEquals", "crash", "malformed", "BinaryData = True\n", "BinaryData = True\nNDK\n"));
  c.push_back(header_edit("KeyOfThreeHundredCharacters", "crash", "huge", "BinaryData = True\n",
                          "BinaryData = True\n" + std::string(300, 'K') + " = 1\n"));
  c.push_back(volume("UnknownExtension", "unclear", "name", "tissue.png", [] { return mha(); }));
  // Detached data.
  c.push_back({"DataFileMissing", "volume", "unclear", "special file", [](const fs::path& dir) {
                 write_text(dir / "tissue.mhd", mha_header("tissue.raw"));
                 return mesh_volume("tissue.mhd");
               }});
  c.push_back({"DataFileIsDevZero", "volume", "hang", "special file", [](const fs::path& dir) {
                 write_text(dir / "tissue.mhd", mha_header("/dev/zero"));
                 return mesh_volume("tissue.mhd");
               }});
  c.push_back({"DataFileIsAFifo", "volume", "hang", "special file", [](const fs::path& dir) {
                 write_text(dir / "tissue.mhd", mha_header("tissue.raw"));
                 make_fifo(dir / "tissue.raw");
                 return mesh_volume("tissue.mhd");
               }});
  c.push_back({"DataFileIsAFolder", "volume", "unclear", "special file", [](const fs::path& dir) {
                 write_text(dir / "tissue.mhd", mha_header("tissue.raw"));
                 fs::create_directories(dir / "tissue.raw");
                 return mesh_volume("tissue.mhd");
               }});
  c.push_back({"DataFileOfSixteenGigabytes", "volume", "hang", "huge", [](const fs::path& dir) {
                 write_text(dir / "tissue.mhd", replaced(mha_header("tissue.raw"), "DimSize = 16 16 16", "DimSize = 2048 2048 4096"));
                 make_sparse(dir / "tissue.raw", 16ull << 30);
                 return mesh_volume("tissue.mhd");
               }});
  c.push_back({"VolumeIsAFifo", "volume", "hang", "special file", [](const fs::path& dir) {
                 make_fifo(dir / "tissue.mha");
                 return mesh_volume("tissue.mha");
               }});
  c.push_back({"VolumeIsDevZero", "volume", "hang", "special file", [](const fs::path& dir) {
                 fs::create_symlink("/dev/zero", dir / "tissue.mha");
                 return mesh_volume("tissue.mha");
               }});
  // NRRD and VTK image data.
  c.push_back(volume("NrrdNegativeSpacing", "nonsense", "absurd", "tissue.nrrd", [] { return nrrd("spacings: 1 1 1", "spacings: 1 -1 1"); }));
  c.push_back(volume("NrrdUnknownEncoding", "unclear", "malformed", "tissue.nrrd", [] { return nrrd("encoding: raw", "encoding: zstd"); }));
  c.push_back(volume("NrrdGzipGarbage", "crash", "malformed", "tissue.nrrd", [] { return nrrd("encoding: raw", "encoding: gzip"); }));
  c.push_back(volume("NrrdSizesHuge", "hang", "huge", "tissue.nrrd", [] { return nrrd("sizes: 16 16 16", "sizes: 100000 100000 100000"); }));
  c.push_back(volume("NrrdTextHeaderCutMidLine", "hang", "truncated", "tissue.nrrd", [] {
    return std::string("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 8 8 8\nencoding: ascii\nspacings: 1 1");
  }));
  c.push_back(volume("NrrdNoMagic", "unclear", "malformed", "tissue.nrrd", [] { return nrrd("NRRD0004", "NRRX0004"); }));
  c.push_back(volume("VtiTruncated", "unclear", "truncated", "tissue.vti", [] {
    return std::string("<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"0.1\">\n  <ImageData WholeExtent=\"0 15 0 15 0 15\" Origin=\"0 0 0\" Spacing=\"1 1 1\">\n    <Piece Extent=\"0 15");
  }));
  c.push_back(volume("VtiNegativeSpacing", "nonsense", "absurd", "tissue.vti", [] {
    std::string values;
    const std::string ball = ball_voxels();
    for (char v : ball) values += std::to_string(static_cast<unsigned char>(v)) + " ";
    return "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"0.1\">\n  <ImageData WholeExtent=\"0 15 0 15 0 15\" Origin=\"0 0 0\" Spacing=\"1 -1 1\">\n"
           "    <Piece Extent=\"0 15 0 15 0 15\">\n      <PointData Scalars=\"s\">\n        <DataArray type=\"UInt8\" Name=\"s\" format=\"ascii\">" +
           values + "</DataArray>\n      </PointData>\n    </Piece>\n  </ImageData>\n</VTKFile>\n";
  }));
  // Tracked sweeps (`reconstruct`).
  const auto sweep_case = [](const std::string& name, const std::string& guards, const std::string& form, const std::string& from,
                             const std::string& to) {
    return Case{name, "volume", guards, form, [=](const fs::path& dir) {
                  write_text(dir / "sweep.igs.mha", sweep(from, to));
                  write_text(dir / "calibration.xml", calibration_text());
                  return Invocation{{"reconstruct", "sweep.igs.mha", "--calibration", "calibration.xml", "--out", "out/volume.mha"}, "sweep.igs.mha"};
                }};
  };
  c.push_back(sweep_case("SweepFrameWithoutPose", "unclear", "wrong shape", "Seq_Frame0001_ProbeToTrackerTransform = ", "Seq_Frame0001_ProbeToTrackerTransfrom = "));
  c.push_back(sweep_case("SweepPoseNaN", "nonsense", "non-finite", "1 0 0 0 0 1 0 0 0 0 1 2 0 0 0 1", "1 0 0 0 0 1 0 0 0 0 1 nan 0 0 0 1"));
  c.push_back(sweep_case("SweepPoseOfTwelveNumbers", "unclear", "wrong shape", "1 0 0 0 0 1 0 0 0 0 1 2 0 0 0 1", "1 0 0 0 0 1 0 0 0 0 1 2"));
  c.push_back(sweep_case("SweepPoseA1e300Shift", "nonsense", "absurd", "1 0 0 0 0 1 0 0 0 0 1 2 0 0 0 1", "1 0 0 0 0 1 0 0 0 0 1 1e300 0 0 0 1"));
  c.push_back(sweep_case("SweepPoseNotRigid", "nonsense", "absurd", "1 0 0 0 0 1 0 0 0 0 1 2 0 0 0 1", "1000 0 0 0 0 1 0 0 0 0 1 2 0 0 0 1"));
  c.push_back(sweep_case("SweepLineWithoutEquals", "crash", "malformed", "Seq_Frame0000_ProbeToTrackerTransformStatus = OK\n",
                         "Seq_Frame0000_ProbeToTrackerTransformStatus = OK\nNDK\n"));
  c.push_back(sweep_case("SweepOfAMillionFrames", "hang", "huge", "DimSize = 8 8 3", "DimSize = 8 8 1000000"));
  c.push_back({"SweepIsAFifo", "volume", "hang", "special file", [](const fs::path& dir) {
                 make_fifo(dir / "sweep.igs.mha");
                 write_text(dir / "calibration.xml", calibration_text());
                 return Invocation{{"reconstruct", "sweep.igs.mha", "--calibration", "calibration.xml", "--out", "out/volume.mha"}, "sweep.igs.mha"};
               }});
  c.push_back({"SweepSparseFourGigabytesWithoutNewline", "volume", "hang", "huge", [](const fs::path& dir) {
                 make_sparse(dir / "sweep.igs.mha", 4ull << 30);
                 write_text(dir / "calibration.xml", calibration_text());
                 return Invocation{{"reconstruct", "sweep.igs.mha", "--calibration", "calibration.xml", "--out", "out/volume.mha"}, "sweep.igs.mha"};
               }});
  return c;
}

}  // namespace fetouch::testing::hostile

// Calibrations: `fetouch reconstruct SWEEP --calibration FILE.xml` on broken PLUS configuration files.
#include <string>

#include "tests/hostile/hostile_case.h"

namespace fetouch::testing::hostile {

namespace {

const char* const kMatrix = "0.1 0 0 0  0 0.1 0 0  0 0 0.1 0  0 0 0 1";

Invocation reconstruct(const fs::path& dir, const std::string& calibration, int exit_code = 2) {
  write_text(dir / "sweep.igs.mha", sweep_text());
  return {{"reconstruct", "sweep.igs.mha", "--calibration", calibration, "--out", "out/volume.mha"}, calibration, exit_code};
}

Case xml(const std::string& name, const std::string& guards, const std::string& form, const std::function<std::string()>& text,
         int exit_code = 2) {
  return {name, "calibration", guards, form, [=](const fs::path& dir) {
            write_text(dir / "calibration.xml", text());
            return reconstruct(dir, "calibration.xml", exit_code);
          }};
}

Case matrix(const std::string& name, const std::string& guards, const std::string& form, const std::string& value) {
  return xml(name, guards, form, [value] { return replaced(calibration_text(), kMatrix, value); });
}

}  // namespace

std::vector<Case> calibration_cases() {
  std::vector<Case> c;
  c.push_back(xml("ValidCalibration", "valid", "name", calibration_text, 0));
  // Attributes that crashed the regular-expression parser before issue 17.
  c.push_back(matrix("MegabyteAttribute", "crash", "huge", std::string(1u << 20, '1')));
  c.push_back(matrix("WhitespaceOnlyMatrix", "crash", "malformed", std::string(100000, ' ')));
  c.push_back(xml("MegabyteOfAttributes", "crash", "huge", [] {  // well formed, so accepted
    std::string attributes;
    for (int i = 0; i < 50000; ++i) attributes += " a" + std::to_string(i) + "=\"x\"";
    return replaced(calibration_text(), "<Transform ", "<Transform" + attributes + " ");
  }, 0));
  // Matrices.
  c.push_back(matrix("FifteenNumbers", "unclear", "wrong shape", "0.1 0 0 0  0 0.1 0 0  0 0 0.1 0  0 0 0"));
  c.push_back(matrix("SeventeenNumbers", "unclear", "wrong shape", std::string(kMatrix) + " 1"));
  c.push_back(matrix("WordsInMatrix", "unclear", "wrong shape", "a b c d e f g h i j k l m n o p"));
  c.push_back(matrix("NaNInMatrix", "nonsense", "non-finite", "0.1 0 0 0  0 nan 0 0  0 0 0.1 0  0 0 0 1"));
  c.push_back(matrix("InfinityInMatrix", "nonsense", "non-finite", "0.1 0 0 0  0 0.1 0 0  0 0 0.1 inf  0 0 0 1"));
  c.push_back(matrix("ZeroMatrix", "nonsense", "absurd", "0 0 0 0  0 0 0 0  0 0 0 0  0 0 0 0"));
  c.push_back(matrix("PixelOfAKilometre", "nonsense", "absurd", "1e6 0 0 0  0 1e6 0 0  0 0 1e6 0  0 0 0 1"));
  c.push_back(matrix("ProjectiveLastRow", "nonsense", "absurd", "0.1 0 0 0  0 0.1 0 0  0 0 0.1 0  1 2 3 4"));
  c.push_back(matrix("MirroredAndSheared", "nonsense", "absurd", "0.1 0.5 0 0  0 -0.1 0 0  0 0 0.1 0  0 0 0 1"));
  c.push_back(matrix("Translation1e300", "nonsense", "absurd", "0.1 0 0 1e300  0 0.1 0 0  0 0 0.1 0  0 0 0 1"));
  // XML.
  c.push_back(xml("NoImageToProbe", "unclear", "wrong shape", [] { return replaced(calibration_text(), "From=\"Image\"", "From=\"Stylus\""); }));
  c.push_back(xml("NoMatrixAttribute", "unclear", "wrong shape", [] { return replaced(calibration_text(), "Matrix=", "Matrx="); }));
  c.push_back(xml("UnclosedTag", "unclear", "malformed", [] { return replaced(calibration_text(), " />", ""); }));
  c.push_back(xml("UnclosedQuote", "unclear", "malformed", [] { return replaced(calibration_text(), "0 0 0 1\" />", "0 0 0 1 />"); }));
  c.push_back(xml("TwoImageToProbe", "nonsense", "malformed", [] {
    const std::string t = calibration_text();
    const auto at = t.find("    <Transform");
    const auto end = t.find("/>", at) + 3;
    return t.substr(0, end) + replaced(t.substr(at, end - at), "0.1 0 0 0", "0.2 0 0 0") + t.substr(end);
  }));
  c.push_back(xml("DeeplyNested", "crash", "malformed", [] {
    std::string open, close;
    for (int i = 0; i < 100000; ++i) open += "<a>", close += "</a>";
    return open + calibration_text() + close;
  }));
  c.push_back(xml("Empty", "unclear", "truncated", [] { return std::string(); }));
  c.push_back(xml("CutInTheMatrix", "unclear", "truncated", [] {
    const std::string t = calibration_text();
    return t.substr(0, t.find(kMatrix) + 10);
  }));
  c.push_back(xml("Garbage", "unclear", "malformed", [] { return garbage(4096, 12); }));
  c.push_back(xml("NulBytes", "nonsense", "malformed", [] { return replaced(calibration_text(), "Image", std::string("Im\0ge", 5)); }));
  c.push_back({"SparseGigabyte", "calibration", "hang", "huge", [](const fs::path& dir) {
                 make_sparse(dir / "calibration.xml", 1ull << 30);
                 return reconstruct(dir, "calibration.xml");
               }});
  c.push_back({"Fifo", "calibration", "hang", "special file", [](const fs::path& dir) {
                 make_fifo(dir / "calibration.xml");
                 return reconstruct(dir, "calibration.xml");
               }});
  c.push_back({"DevZero", "calibration", "hang", "special file", [](const fs::path& dir) { return reconstruct(dir, "/dev/zero"); }});
  c.push_back({"Folder", "calibration", "unclear", "special file", [](const fs::path& dir) {
                 fs::create_directories(dir / "calibration.xml");
                 return reconstruct(dir, "calibration.xml");
               }});
  c.push_back({"UnicodeName", "calibration", "valid", "name", [](const fs::path& dir) {
                 write_text(dir / "калибровка 校准.xml", calibration_text());
                 return reconstruct(dir, "калибровка 校准.xml", 0);
               }});
  c.push_back({"OutputOverTheCalibration", "calibration", "overwrite", "output over input", [](const fs::path& dir) {
                 write_text(dir / "calibration.mha", calibration_text());
                 write_text(dir / "sweep.igs.mha", sweep_text());
                 return Invocation{{"reconstruct", "sweep.igs.mha", "--calibration", "calibration.mha", "--out", "calibration.mha"}, "calibration.mha"};
               }});
  c.push_back({"OutputOverTheSweep", "calibration", "overwrite", "output over input", [](const fs::path& dir) {
                 write_text(dir / "calibration.xml", calibration_text());
                 write_text(dir / "sweep.igs.mha", sweep_text());
                 return Invocation{{"reconstruct", "sweep.igs.mha", "--calibration", "calibration.xml", "--out", "./sweep.igs.mha"}, "sweep.igs.mha"};
               }});
  return c;
}

}  // namespace fetouch::testing::hostile

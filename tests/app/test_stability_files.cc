// `fetouch stability --region/--volume/--step`: the files it writes, read back and checked against
// closed forms (Jury's test on the characteristic polynomials of ARCHITECTURE.md section 3, the
// P-ZOH pole). The PNGs need a display: ctest runs under xvfb-run (scripts/quickstart test).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <vector>

#include "haptics/stability_analysis.h"
#include "tests/support/run_command.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  int column(const std::string& name) const {
    for (size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return static_cast<int>(i);
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
};

Csv read_csv(const fs::path& path) {
  Csv csv;
  std::istringstream in(read_file_text(path));
  std::string line;
  std::getline(in, line);
  std::istringstream head(line);
  for (std::string cell; std::getline(head, cell, ',');) csv.header.push_back(cell);
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) row.push_back(std::stod(cell));
    csv.rows.push_back(row);
  }
  return csv;
}

// A PNG's signature and IHDR size, and whether it holds more than one colour byte value (a blank
// image compresses to a few hundred bytes; a drawn chart does not).
void expect_png(const fs::path& path, int width, int height) {
  const std::string bytes = read_file_text(path);
  ASSERT_GT(bytes.size(), 24u) << path;
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const auto be32 = [&](size_t at) {
    return (std::uint32_t(std::uint8_t(bytes[at])) << 24) | (std::uint32_t(std::uint8_t(bytes[at + 1])) << 16) |
           (std::uint32_t(std::uint8_t(bytes[at + 2])) << 8) | std::uint32_t(std::uint8_t(bytes[at + 3]));
  };
  EXPECT_EQ(be32(16), static_cast<std::uint32_t>(width));
  EXPECT_EQ(be32(20), static_cast<std::uint32_t>(height));
  EXPECT_GT(bytes.size(), 8000u) << "an almost empty image: " << path;
}

bool has_display() {
  const char* display = std::getenv("DISPLAY");
  return display && *display;
}
#define REQUIRE_DISPLAY() \
  ASSERT_TRUE(has_display()) << "this test draws PNGs with VTK: run it under xvfb-run -a (scripts/quickstart test does)"

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_stability_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

bool jury_cubic(double a3, double a2, double a1, double a0) { return haptics::jury_stable({a3, a2, a1, a0}); }

// PI with FOH, N = 50, K0 = 1, B0 = 0: every grid point's verdict equals Jury's test on the cubic
//   (K0+B0) z^3 - (K0+2B0) z^2 + (Kh + B0 + I (N-1)/2) z + (I (N+1)/2 - Kh),
// and the spectral radius equals its largest root modulus.
TEST(StabilityFiles, PiFohRegionBoundaryIsJurys) {
  REQUIRE_DISPLAY();
  const fs::path dir = scratch("region");
  const auto r = run_command(fetouch("stability --local-model pi --hold foh -N 50 --k0 1 --b0 0 --points 81 --region " +
                                     (dir / "pi_foh").string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Csv csv = read_csv(dir / "pi_foh.csv");
  ASSERT_EQ(csv.rows.size(), 81u * 81u);
  const int kh_c = csv.column("kh"), ni_c = csv.column("ni"), r_c = csv.column("spectral_radius"), s_c = csv.column("stable");
  int stable = 0, unstable = 0;
  double kh_max = 0;
  for (const auto& row : csv.rows) {
    const double kh = row[kh_c], ni = row[ni_c], i = ni / 50, n = 50;
    const double a3 = 1, a2 = -1, a1 = kh + i * (n - 1) / 2, a0 = i * (n + 1) / 2 - kh;
    double modulus = 0;
    for (const auto& z : haptics::polynomial_roots({a3, a2, a1, a0})) modulus = std::max(modulus, std::abs(z));
    EXPECT_NEAR(row[r_c], modulus, 1e-6 * std::max(1.0, modulus)) << kh << " " << ni;
    if (std::abs(modulus - 1) < 1e-9) continue;  // on the boundary (N I = 0: the integrator's pole at 1)
    EXPECT_EQ(row[s_c] == 1, jury_cubic(a3, a2, a1, a0)) << kh << " " << ni;
    (row[s_c] == 1 ? stable : unstable)++;
    if (row[s_c] == 1) kh_max = std::max(kh_max, kh);
  }
  // The axes were fitted around the region: both verdicts are well represented.
  EXPECT_GT(stable, 1000);
  EXPECT_GT(unstable, 300);
  expect_png(dir / "pi_foh.png", 1000, 700);
  fs::remove_all(dir);
}

// PI with ZOH over three K0: each verdict is the four inequalities of the architecture page, and
// the region grows with K0.
TEST(StabilityFiles, PiZohVolumeFollowsTheFourInequalities) {
  REQUIRE_DISPLAY();
  const fs::path dir = scratch("volume");
  const auto r = run_command(fetouch("stability --local-model pi --hold zoh --b0 0.1 --points 41 --k0-values 0.5 1 2 --volume " +
                                     (dir / "vol.csv").string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Csv csv = read_csv(dir / "vol.csv");
  ASSERT_EQ(csv.rows.size(), 3u * 41u * 41u);
  std::map<double, int> stable_per_k0;
  const double b0 = 0.1;
  for (const auto& row : csv.rows) {
    const double k0 = row[0], kh = row[1], ni = row[2], radius = row[3];
    if (std::abs(radius - 1) < 1e-9) continue;
    const bool jury = ni > 0 && ni < k0 + kh && ni > kh - k0 - 2 * b0 && 2 * kh < 2 * k0 + 4 * b0 + ni;
    EXPECT_EQ(row[4] == 1, jury) << k0 << " " << kh << " " << ni;
    stable_per_k0[k0] += row[4] == 1;
  }
  ASSERT_EQ(stable_per_k0.size(), 3u);
  EXPECT_LT(stable_per_k0[0.5], stable_per_k0[1.0]);
  EXPECT_LT(stable_per_k0[1.0], stable_per_k0[2.0]);
  expect_png(dir / "vol.png", 1000, 700);
  fs::remove_all(dir);
}

// P with ZOH, K0 = 0.2, Kh = 0.19: the surface's distance to its final value shrinks by the pole
// -0.95 every frame, and the force settles at K0 Kh / (K0 + Kh).
TEST(StabilityFiles, StepResponseRingsWithThePole) {
  REQUIRE_DISPLAY();
  const fs::path dir = scratch("step");
  const auto r = run_command(fetouch("stability --local-model p --k0 0.2 --kh 0.19 --duration 8 --step " + (dir / "ring").string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Csv csv = read_csv(dir / "ring.csv");
  ASSERT_EQ(csv.header, (std::vector<std::string>{"t_s", "device", "proxy", "surface", "force"}));
  ASSERT_EQ(csv.rows.size(), 8000u);
  const double steady_surface = 0.19 / 0.39, steady_force = 0.2 * 0.19 / 0.39;
  for (int j = 2; j < 60; ++j) {  // frames of 50 ticks; the surface is constant within one
    const double now = csv.rows[50 * j + 10][3] - steady_surface, next = csv.rows[50 * (j + 1) + 10][3] - steady_surface;
    EXPECT_NEAR(next / now, -0.95, 1e-6) << j;
  }
  EXPECT_NEAR(csv.rows.back()[4], steady_force, 0.02 * steady_force);
  EXPECT_EQ(csv.rows[100][0], 0.1);
  expect_png(dir / "ring.png", 1000, 700);
  fs::remove_all(dir);
}

TEST(StabilityFiles, WithoutADisplayTheCsvIsWrittenAndTheUserToldHowToGetThePng) {
  const fs::path dir = scratch("nodisplay");
  const auto r = run_command("env -u DISPLAY " + fetouch("stability --local-model p --region " + (dir / "p").string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "p.csv"));
  EXPECT_FALSE(fs::exists(dir / "p.png"));
  EXPECT_NE(r.err.find("xvfb-run -a"), std::string::npos) << r.err;
  fs::remove_all(dir);
}

TEST(StabilityFiles, UnwritablePathIsAnErrorNamingIt) {
  const auto r = run_command(fetouch("stability --local-model p --region /proc/no/such/region"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("/proc/no/such"), std::string::npos) << r.err;
  const auto v = run_command(fetouch("stability --local-model p --volume /tmp/x"));
  EXPECT_EQ(v.exit_code, 2);
  EXPECT_NE(v.err.find("--volume needs"), std::string::npos) << v.err;
}

}  // namespace
}  // namespace fetouch::testing

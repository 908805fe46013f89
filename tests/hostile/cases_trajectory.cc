// Trajectories: `fetouch replay SCENE --trajectory FILE.csv` on broken probe trajectories.
#include <cstdio>
#include <string>

#include "tests/hostile/hostile_case.h"

namespace fetouch::testing::hostile {

namespace {

const char* const kHeader = "t_s,x_m,y_m,z_m\n";
const char* const kPoke =
    "0,0.05,0.04,0.06\n0.5,0.05,0.04,0.06\n1,0.05,0.04,0.052\n2,0.05,0.04,0.052\n2.5,0.05,0.04,0.06\n";

Invocation replay(const fs::path& dir, const std::string& trajectory, int exit_code = 2) {
  write_block_scene(dir);
  return {{"replay", "scene.yaml", "--trajectory", trajectory, "--out", "out", "--mesh-every", "0"}, trajectory, exit_code};
}

Case csv(const std::string& name, const std::string& guards, const std::string& form, const std::function<std::string()>& text) {
  return {name, "trajectory", guards, form, [=](const fs::path& dir) {
            write_text(dir / "probe.csv", text());
            return replay(dir, "probe.csv");
          }};
}

Case csv(const std::string& name, const std::string& guards, const std::string& form, const std::string& text) {
  return csv(name, guards, form, [text] { return text; });
}

}  // namespace

std::vector<Case> trajectory_cases() {
  const std::string h = kHeader, poke = kPoke;
  std::vector<Case> c;
  c.push_back({"ValidCrLfTrajectoryInAScene", "trajectory", "valid", "malformed", [h, poke](const fs::path& dir) {
                 std::string text = h + poke;
                 for (std::size_t at = text.find('\n'); at != std::string::npos; at = text.find('\n', at + 2)) text.insert(at, "\r");
                 write_text(dir / "probe.csv", text);
                 write_block_scene(dir, "scene.yaml", [](std::string t) { return replaced(t, "trajectories/poke_block.csv", "probe.csv"); });
                 return Invocation{{"check", "scene.yaml"}, "", 0};
               }});
  // Not finite, not increasing.
  c.push_back(csv("NaNPosition", "nonsense", "non-finite", h + "0,0.05,0.04,0.06\n1,0.05,nan,0.05\n2,0.05,0.04,0.06\n"));
  c.push_back(csv("NaNTime", "nonsense", "non-finite", h + "0,0.05,0.04,0.06\nnan,0.05,0.04,0.05\n2,0.05,0.04,0.06\n"));
  c.push_back(csv("InfinitePosition", "nonsense", "non-finite", h + "0,0.05,0.04,0.06\n1,inf,0.04,0.05\n2,0.05,0.04,0.06\n"));
  c.push_back(csv("NumberPastDouble", "nonsense", "non-finite", h + "0,0.05,0.04,0.06\n1,1e400,0.04,0.05\n2,0.05,0.04,0.06\n"));
  c.push_back(csv("RepeatedTimestamps", "nonsense", "wrong shape", h + "0,0.05,0.04,0.06\n1,0.05,0.04,0.05\n1,0.05,0.04,0.055\n2,0.05,0.04,0.06\n"));
  c.push_back(csv("TimeRunningBackwards", "nonsense", "wrong shape", h + "0,0.05,0.04,0.06\n2,0.05,0.04,0.05\n1,0.05,0.04,0.06\n"));
  c.push_back(csv("NegativeStartTime", "nonsense", "absurd", h + "-5,0.05,0.04,0.06\n1,0.05,0.04,0.05\n2,0.05,0.04,0.06\n"));
  // Absurd magnitudes.
  c.push_back(csv("PositionsInMillimetres", "nonsense", "absurd", h + "0,50,40,60\n1,50,40,52\n2,50,40,60\n"));
  c.push_back(csv("Positions1e300", "nonsense", "absurd", h + "0,0.05,0.04,0.06\n1,1e300,0.04,0.05\n2,0.05,0.04,0.06\n"));
  c.push_back(csv("SpanOf1e5Seconds", "hang", "absurd", h + "0,0.05,0.04,0.06\n100000,0.05,0.04,0.05\n"));
  c.push_back(csv("SpanOf1e300Seconds", "hang", "absurd", h + "0,0.05,0.04,0.06\n1e300,0.05,0.04,0.05\n"));
  c.push_back(csv("TimeStepOfAFemtosecond", "nonsense", "absurd", h + "0,0.05,0.04,0.06\n1e-15,0.05,0.04,0.05\n1,0.05,0.04,0.06\n"));
  c.push_back(csv("ProbeAt100MetresPerSecond", "nonsense", "absurd", h + "0,0.05,0.04,0.06\n0.001,0.05,0.04,0.16\n1,0.05,0.04,0.06\n"));
  // Wrong shapes.
  c.push_back(csv("ThreeColumns", "unclear", "wrong shape", h + "0,0.05,0.04\n1,0.05,0.04\n"));
  c.push_back(csv("FiveColumns", "unclear", "wrong shape", h + "0,0.05,0.04,0.06,1\n1,0.05,0.04,0.05,1\n"));
  c.push_back(csv("WordsForNumbers", "unclear", "wrong shape", h + "0,0.05,0.04,0.06\n1,five,0.04,0.05\n"));
  c.push_back(csv("SemicolonSeparated", "unclear", "wrong shape", "t_s;x_m;y_m;z_m\n0;0.05;0.04;0.06\n1;0.05;0.04;0.05\n"));
  c.push_back(csv("DecimalCommas", "unclear", "wrong shape", h + "0,0,05,0,04,0,06\n1,0,05,0,04,0,05\n"));
  c.push_back(csv("OneRow", "unclear", "truncated", h + "0,0.05,0.04,0.06\n"));
  c.push_back(csv("HeaderOnly", "unclear", "truncated", h));
  c.push_back(csv("Empty", "unclear", "truncated", ""));
  c.push_back(csv("CutMidRow", "unclear", "truncated", h + "0,0.05,0.04,0.06\n1,0.05,0.04,0.05\n2,0.05,0."));
  c.push_back(csv("NulBytes", "nonsense", "malformed", h + std::string("0,0.05,0.04,0.06\n1,0.05\0,0.04,0.05\n", 36)));
  c.push_back(csv("BinaryGarbage", "unclear", "malformed", garbage(4096, 21)));
  c.push_back(csv("AYamlSceneInstead", "unclear", "malformed", read_text(source_dir() / "config/scenes/block_press.yaml")));
  c.push_back(csv("TenMegabyteLine", "unclear", "huge", [h] { return h + "0,0.05,0.04,0.06\n1," + std::string(10u << 20, '5') + ",0.04,0.05\n"; }));
  c.push_back(csv("MillionRowsInATenthOfASecond", "hang", "huge", [] {
    std::string t = kHeader;
    t.reserve(40u << 20);
    char row[64];
    for (int i = 0; i < 1'000'000; ++i) t.append(row, static_cast<std::size_t>(std::snprintf(row, sizeof row, "%.7f,0.05,0.04,0.06\n", i * 1e-7)));
    return t;
  }));
  // Special files.
  c.push_back({"Fifo", "trajectory", "hang", "special file", [](const fs::path& dir) {
                 make_fifo(dir / "probe.csv");
                 return replay(dir, "probe.csv");
               }});
  c.push_back({"DevZero", "trajectory", "nonsense", "special file", [](const fs::path& dir) { return replay(dir, "/dev/zero"); }});
  c.push_back({"Folder", "trajectory", "unclear", "special file", [](const fs::path& dir) {
                 fs::create_directories(dir / "probe.csv");
                 return replay(dir, "probe.csv");
               }});
  c.push_back({"SparseGigabyte", "trajectory", "hang", "huge", [](const fs::path& dir) {
                 make_sparse(dir / "probe.csv", 1ull << 30);
                 return replay(dir, "probe.csv");
               }});
  c.push_back({"OutputOverTheTrajectory", "trajectory", "overwrite", "output over input", [h, poke](const fs::path& dir) {
                 write_text(dir / "out" / "recording.h5", h + poke);  // a CSV named as the recording the replay writes
                 write_block_scene(dir);
                 return Invocation{{"replay", "scene.yaml", "--trajectory", "out/recording.h5", "--out", "out"}, "recording.h5"};
               }});
  c.push_back({"UnicodeNameMissing", "trajectory", "unclear", "name", [](const fs::path& dir) {
                 return replay(dir, "траектория_軌跡.csv");
               }});
  return c;
}

}  // namespace fetouch::testing::hostile

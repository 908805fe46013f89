// Scenes: `fetouch check SCENE` on the block scene broken in every way a scene file can be.
#include <string>
#include <utility>

#include "tests/hostile/hostile_case.h"

namespace fetouch::testing::hostile {

namespace {

Invocation check(const std::string& scene, int exit_code = 2) { return {{"check", scene}, scene, exit_code}; }

// The block scene with `from` replaced by `to`, checked.
Case edit(const std::string& name, const std::string& guards, const std::string& form, const std::string& from,
          const std::string& to, int exit_code = 2) {
  return {name, "scene", guards, form, [=](const fs::path& dir) {
            write_block_scene(dir, "scene.yaml", [&](std::string t) { return replaced(t, from, to); });
            return check("scene.yaml", exit_code);
          }};
}

// A scene file with exactly these bytes.
Case raw(const std::string& name, const std::string& guards, const std::string& form,
         const std::function<std::string()>& bytes) {
  return {name, "scene", guards, form, [=](const fs::path& dir) {
            write_block_scene(dir, "base.yaml");
            write_text(dir / "scene.yaml", bytes());
            return check("scene.yaml");
          }};
}

std::string block_text() { return read_text(source_dir() / "config/scenes/block_press.yaml"); }

}  // namespace

std::vector<Case> scene_cases() {
  std::vector<Case> c;
  // Absurd magnitudes, each with its unit in the key: accepted before issue 17.
  const std::pair<const char*, std::pair<const char*, const char*>> absurd[] = {
      {"BoxOf1e300Metres", {"size_m: [0.10, 0.08, 0.05]", "size_m: [1e300, 0.08, 0.05]"}},
      {"BoxOfANanometre", {"size_m: [0.10, 0.08, 0.05]", "size_m: [1e-9, 0.08, 0.05]"}},
      {"BoxOfAKilometre", {"size_m: [0.10, 0.08, 0.05]", "size_m: [1000, 800, 500]"}},
      {"ProbeRadius10m", {"radius_m: 0.005", "radius_m: 10"}},
      {"ProbeRadiusANanometre", {"radius_m: 0.005", "radius_m: 1e-9"}},
      {"ForceLimit1e300N", {"max_force_n: 3.3", "max_force_n: 1e300"}},
      {"ForceLimit1000N", {"max_force_n: 3.3", "max_force_n: 1000"}},
      {"Modulus1e300Pa", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: 1e300"}},
      {"ModulusAMicropascal", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: 1e-6"}},
      {"ModulusOfSteel", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: 2e11"}},
      {"DensityOfANeutronStar", {"density_kg_per_m3: 1050", "density_kg_per_m3: 1e17"}},
      {"DensityOfAir", {"density_kg_per_m3: 1050", "density_kg_per_m3: 1.2"}},
      {"HapticRateAGigahertz", {"rate_hz: 1000", "rate_hz: 1e9"}},
      {"HapticRate1Hz", {"rate_hz: 1000", "rate_hz: 1"}},
      {"SolverRateOncePerCentury", {"rate_hz: 20", "rate_hz: 3e-10"}},
      {"NewtonToleranceAboveOne", {"relative_tolerance: 1.0e-8", "relative_tolerance: 5"}},
      {"NewtonIterationsABillion", {"max_iterations: 25", "max_iterations: 1000000000"}},
      {"MarginAboveOne", {"robustness_margin: 0.3", "robustness_margin: 1e300"}},
      {"WatchdogOfAYear", {"max_force_n: 3.3", "max_force_n: 3.3\n  watchdog_timeout_s: 3.2e7"}},
      {"ForceRate1e300", {"max_force_n: 3.3", "max_force_n: 3.3\n  max_force_rate_n_per_s: 1e300"}},
      {"RefinementsAThousand", {"refinements: 2", "refinements: 1000"}},
  };
  for (const auto& [name, change] : absurd) c.push_back(edit(name, "nonsense", "absurd", change.first, change.second));

  // Not finite numbers.
  const std::pair<const char*, std::pair<const char*, const char*>> nonfinite[] = {
      {"ModulusNaN", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: .nan"}},
      {"ModulusInfinite", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: .inf"}},
      {"BoxInfinite", {"size_m: [0.10, 0.08, 0.05]", "size_m: [.inf, 0.08, 0.05]"}},
      {"ProbeRadiusMinusInfinity", {"radius_m: 0.005", "radius_m: -.inf"}},
      {"ForceLimitNaN", {"max_force_n: 3.3", "max_force_n: .NaN"}},
      {"DensityInfinite", {"density_kg_per_m3: 1050", "density_kg_per_m3: .Inf"}},
      {"PoissonNaN", {"poisson_ratio: 0.45", "poisson_ratio: .nan"}},
      {"RateNaN", {"rate_hz: 20", "rate_hz: nan"}},
      {"Modulus1e400", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: 1e400"}},
  };
  for (const auto& [name, change] : nonfinite) c.push_back(edit(name, "nonsense", "non-finite", change.first, change.second));

  // Wrong types and shapes.
  const std::pair<const char*, std::pair<const char*, const char*>> types[] = {
      {"StrTaggedNumber", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: !!str 5000"}},
      {"NumberAsList", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: [5000]"}},
      {"NumberAsMap", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: {value: 5000}"}},
      {"NumberAsBoolean", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: true"}},
      {"NumberWithUnit", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: 5 kPa"}},
      {"VectorAsWord", {"size_m: [0.10, 0.08, 0.05]", "size_m: big"}},
      {"VectorOfFour", {"size_m: [0.10, 0.08, 0.05]", "size_m: [0.10, 0.08, 0.05, 0.01]"}},
      {"ProbesAsWord", {"probes:\n  - name: tool", "probes: tool\nxprobes:\n  - name: tool"}},
      {"MeshAsNumber", {"mesh:\n  generate:", "mesh: 5\nxmesh:\n  generate:"}},
      {"FloatTaggedWord", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: !!float soft"}},
      {"CustomTag", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: !pascal 5000"}},
      {"NullModulus", {"youngs_modulus_pa: 5000", "youngs_modulus_pa: ~"}},
  };
  for (const auto& [name, change] : types) c.push_back(edit(name, "unclear", "wrong shape", change.first, change.second));

  // Malformed text.
  c.push_back(raw("NulByte", "nonsense", "malformed", [] { return replaced(block_text(), "soft tissue block", std::string("soft\0tissue", 11)); }));
  c.push_back(raw("NulByteInComment", "nonsense", "malformed", [] { return replaced(block_text(), "# A soft", std::string("# A\0soft", 8)); }));
  c.push_back(raw("InvalidUtf8", "unclear", "malformed", [] { return replaced(block_text(), "soft tissue block", "soft \xff\xfe tissue"); }));
  c.push_back(raw("TabIndentation", "unclear", "malformed", [] { return replaced(block_text(), "  model: neo_hookean", "\tmodel: neo_hookean"); }));
  c.push_back(raw("UnclosedQuote", "unclear", "malformed", [] { return replaced(block_text(), "name: block_press", "name: \"block_press"); }));
  c.push_back(raw("UnclosedFlow", "unclear", "malformed", [] { return replaced(block_text(), "0.05]", "0.05"); }));
  c.push_back(raw("BinaryGarbage", "unclear", "malformed", [] { return garbage(4096, 17); }));
  c.push_back(raw("DeepNesting", "crash", "malformed", [] { return "name: " + std::string(100000, '[') + std::string(100000, ']') + "\n"; }));
  c.push_back(raw("DeepMappings", "crash", "malformed", [] {
    std::string t = "name: x\nmesh:\n";
    for (int i = 0; i < 5000; ++i) t += std::string(static_cast<std::size_t>(2 * (i + 1)), ' ') + "a:\n";
    return t;
  }));
  c.push_back(raw("AliasBomb", "hang", "malformed", [] {
    std::string t = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
    for (int i = 1; i < 10; ++i) {
      t += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [";
      for (int k = 0; k < 10; ++k) t += std::string(k ? ", " : "") + "*a" + std::to_string(i - 1);
      t += "]\n";
    }
    return block_text() + "description2: *a9\n" + t;
  }));
  c.push_back(raw("UndefinedAlias", "unclear", "malformed", [] { return replaced(block_text(), "youngs_modulus_pa: 5000", "youngs_modulus_pa: *stiff"); }));
  c.push_back(raw("EmptyFile", "unclear", "malformed", [] { return std::string(); }));
  c.push_back(raw("OnlyComments", "unclear", "malformed", [] { return std::string("# nothing here\n# at all\n"); }));
  c.push_back(raw("TwoDocuments", "unclear", "malformed", [] { return block_text() + "---\n" + block_text(); }));
  c.push_back(raw("TopLevelList", "unclear", "wrong shape", [] { return std::string("- name: block\n- units: SI\n"); }));
  c.push_back(raw("TopLevelNumber", "unclear", "wrong shape", [] { return std::string("42\n"); }));
  c.push_back(raw("DuplicateKey", "nonsense", "malformed", [] { return replaced(block_text(), "units: SI", "units: SI\nunits: SI"); }));
  c.push_back(raw("CsvAsScene", "unclear", "wrong shape", [] { return read_text(source_dir() / "config/scenes/trajectories/poke_block.csv"); }));

  // Truncated: the scene cut at eight places.
  for (int tenth : {1, 2, 3, 4, 5, 6, 7, 9})  // cut at 80 % it is a valid scene without probes
    c.push_back(raw("TruncatedAt" + std::to_string(tenth * 10) + "Percent", "unclear", "truncated", [tenth] {
      const std::string t = block_text();
      return t.substr(0, t.size() * static_cast<std::size_t>(tenth) / 10);
    }));

  // Huge.
  c.push_back(raw("TwentyMegabytesOfComments", "hang", "huge", [] {
    std::string t = block_text();
    t.reserve(21u << 20);
    while (t.size() < (20u << 20)) t += "# padding padding padding padding padding padding padding padding\n";
    return t;
  }));
  c.push_back(raw("OneMegabyteName", "unclear", "huge", [] { return replaced(block_text(), "name: block_press", "name: " + std::string(1u << 20, 'x')); }));
  c.push_back(raw("HundredProbes", "nonsense", "huge", [] {
    std::string probes = "probes:\n";
    for (int i = 0; i < 100; ++i)
      probes += "  - name: p" + std::to_string(i) + "\n    radius_m: 0.005\n    device: {type: replay, trajectory: trajectories/poke_block.csv}\n";
    return replaced(block_text(), "probes:\n", probes);
  }));
  c.push_back({"SparseTwoGigabytes", "scene", "hang", "huge", [](const fs::path& dir) {
                 make_sparse(dir / "scene.yaml", 2ull << 30);
                 return check("scene.yaml");
               }});

  // Special files.
  c.push_back({"SceneIsAFifo", "scene", "hang", "special file", [](const fs::path& dir) {
                 make_fifo(dir / "scene.yaml");
                 return check("scene.yaml");
               }});
  c.push_back({"SceneIsDevZero", "scene", "hang", "special file", [](const fs::path& dir) {
                 fs::create_symlink("/dev/zero", dir / "scene.yaml");
                 return check("scene.yaml");
               }});
  c.push_back({"SceneIsDevNull", "scene", "unclear", "special file", [](const fs::path& dir) {
                 fs::create_symlink("/dev/null", dir / "scene.yaml");
                 return check("scene.yaml");
               }});
  c.push_back({"SceneIsAFolder", "scene", "unclear", "special file", [](const fs::path& dir) {
                 fs::create_directories(dir / "scene.yaml");
                 return check("scene.yaml");
               }});
  c.push_back({"SceneIsMissing", "scene", "unclear", "special file", [](const fs::path&) { return check("absent.yaml"); }});
  c.push_back({"TrajectoryIsAFifo", "scene", "hang", "special file", [](const fs::path& dir) {
                 write_block_scene(dir, "scene.yaml", [](std::string t) { return replaced(t, "trajectories/poke_block.csv", "pipe.csv"); });
                 make_fifo(dir / "pipe.csv");
                 return Invocation{{"check", "scene.yaml"}, "pipe.csv"};
               }});
  c.push_back({"SymlinkedSceneIsRead", "scene", "valid", "special file", [](const fs::path& dir) {
                 write_block_scene(dir, "real.yaml");
                 fs::create_symlink("real.yaml", dir / "scene.yaml");
                 return check("scene.yaml", 0);
               }});

  // Names: odd but valid names work; impossible ones are refused with the name.
  c.push_back({"UnicodeName", "scene", "valid", "name", [](const fs::path& dir) {
                 write_block_scene(dir, "ткань_胎児_🫀.yaml");
                 return check("ткань_胎児_🫀.yaml", 0);
               }});
  c.push_back({"SpacesAndQuotesInName", "scene", "valid", "name", [](const fs::path& dir) {
                 write_block_scene(dir, "my \"soft\" 'block' $HOME.yaml");
                 return check("my \"soft\" 'block' $HOME.yaml", 0);
               }});
  c.push_back({"NameLikeAnOption", "scene", "valid", "name", [](const fs::path& dir) {
                 write_block_scene(dir, "-v.yaml");
                 return check("./-v.yaml", 0);
               }});
  c.push_back({"LongestFileName", "scene", "valid", "name", [](const fs::path& dir) {
                 const std::string name = std::string(250, 'n') + ".yaml";
                 write_block_scene(dir, name);
                 return check(name, 0);
               }});
  c.push_back({"FileNameTooLong", "scene", "unclear", "name", [](const fs::path&) {
                 Invocation run = check(std::string(300, 'n') + ".yaml");
                 run.names = std::string(30, 'n') + ".yaml";  // a long name is shown by its two ends
                 return run;
               }});
  c.push_back({"PathBeyondPathMax", "scene", "unclear", "name", [](const fs::path&) {
                 std::string path;
                 for (int i = 0; i < 20; ++i) path += std::string(240, 'd') + "/";
                 return Invocation{{"check", path + "scene.yaml"}, "scene.yaml"};
               }});
  c.push_back({"MeshFileWithUnicodeNameMissing", "scene", "unclear", "name", [](const fs::path& dir) {
                 write_block_scene(dir, "scene.yaml", [](std::string t) {
                   return replaced(t, "  generate:\n    shape: box\n    size_m: [0.10, 0.08, 0.05]\n    refinements: 2\n",
                                   "  file: сетка_网格.vtu\n");
                 });
                 return Invocation{{"check", "scene.yaml"}, "сетка_网格.vtu"};
               }});
  return c;
}

}  // namespace fetouch::testing::hostile

// A real `fetouch replay` session killed with SIGKILL mid-run (issue 6): its recording reopens, its
// header is whole, and it holds every tick, in order, up to at most one second before the kill.
// The session writes recording.partial.h5 and renames it to recording.h5 only when complete, so the
// outputs of an earlier run in the folder are left as they were (issue 17). The MPI session
// directory the killed process leaves in /tmp is removed by the next fetouch that starts MPI.
// The real-time clock ties the recording's time to the wall clock (tick k at k ms after the
// session starts, which the command announces on stderr), so "one second before the kill" is a
// tick number: the I/O thread flushes every half second.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>

#include "app/recording.h"
#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

TEST(ReplayKilled, RecordingHoldsEverySampleUpToASecondBeforeTheKill) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_killed_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string earlier = "the outputs of an earlier run";
  for (const char* name : {"recording.h5", "summary.json"}) std::ofstream(dir / name) << earlier;
  const std::string scene = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes/block_press.yaml";
  int err[2];
  ASSERT_EQ(pipe(err), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    dup2(err[1], 2);
    close(err[0]);
    std::freopen("/dev/null", "w", stdout);
    execl(FETOUCH_BINARY, FETOUCH_BINARY, "replay", "--clock", "realtime", "--mesh-every", "0", "--out",
          dir.c_str(), scene.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  close(err[1]);
  FILE* log = fdopen(err[0], "r");
  char line[512];
  bool started = false;
  while (std::fgets(line, sizeof line, log))
    if (std::string(line).find("replaying") != std::string::npos) {
      started = true;
      break;
    }
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE(started) << "the session never started";
  std::this_thread::sleep_for(std::chrono::milliseconds(2000));
  ASSERT_EQ(kill(child, SIGKILL), 0);
  const double killed_after = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  int status = 0;
  waitpid(child, &status, 0);
  std::fclose(log);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "it finished before the kill";

  for (const char* name : {"recording.h5", "summary.json"}) {
    std::ifstream in(dir / name);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()), earlier) << name;
  }
  const app::Recording r = app::read_recording(dir / "recording.partial.h5");
  EXPECT_NE(r.header.scene_text.find("block_press"), std::string::npos);
  ASSERT_EQ(r.devices.size(), 1u);
  const auto& samples = r.devices[0].samples;
  for (std::size_t k = 0; k < samples.size(); ++k) ASSERT_DOUBLE_EQ(samples[k].time_s, 1e-3 * double(k)) << k;
  const double last = samples.empty() ? -1 : samples.back().time_s;
  // The session's first tick comes 20 ms after it starts; 0.1 s of slack for the announcement's
  // trip through the pipe and the kill's delivery.
  std::printf("killed %.3f s into the session; the recording reaches %.3f s (%zu ticks, %zu frames)\n", killed_after,
              last, samples.size(), r.frames.size());
  EXPECT_GE(last, killed_after - 1.0 - 0.1);
  EXPECT_LT(last, killed_after + 0.05);  // nothing recorded that had not happened
  EXPECT_FALSE(r.frames.empty());

  // A killed process cannot remove its MPI session directory; the next fetouch that starts MPI does
  // (this one, or one of a test run beside it).
  const fs::path orphan = fs::temp_directory_path() / ("fetouch_mpi_" + std::to_string(child));
  const auto next = run_command(fetouch("check " + scene));
  EXPECT_EQ(next.exit_code, 0) << next.err;
  EXPECT_FALSE(fs::exists(orphan)) << orphan << " was left behind";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing

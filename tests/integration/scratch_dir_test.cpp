// The server's scratch folders: what a server killed with SIGKILL leaves behind is removed by
// the next one, and nothing of a running process is touched.
#include "server/scratch_dir.h"

#include <sys/wait.h>
#include <unistd.h>

#include <fstream>

#include <gtest/gtest.h>

namespace bathyslam::server {
namespace {

namespace fs = std::filesystem;

// The pid of a process that has exited (and been reaped): no process has it now.
int a_dead_pid() {
  const pid_t child = fork();
  if (child == 0) _exit(0);
  waitpid(child, nullptr, 0);
  return child;
}

TEST(ScratchDir, TheDefaultFoldersOfDeadServersAreRemovedAndNoOthers) {
  const fs::path temp = fs::temp_directory_path() / ("bathyslam_scratch_test_" + std::to_string(getpid()));
  fs::remove_all(temp);
  const fs::path dead = default_scratch_root(temp, a_dead_pid());
  const fs::path alive = default_scratch_root(temp, getpid());
  const fs::path other = temp / "bathyslam-server-x1";
  const fs::path not_a_folder = default_scratch_root(temp, a_dead_pid());
  fs::create_directories(dead / "bundle.abc123");
  std::ofstream(dead / "bundle.abc123" / "pings.csv") << "time\n";
  fs::create_directories(alive / "bundle.def456");
  fs::create_directories(other);
  fs::create_directories(temp);
  std::ofstream(not_a_folder) << "a file of that name is not a scratch folder\n";

  EXPECT_EQ(remove_dead_servers_scratch(temp), 1);
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(alive / "bundle.def456"));
  EXPECT_TRUE(fs::exists(other));
  EXPECT_TRUE(fs::exists(not_a_folder));
  EXPECT_EQ(remove_dead_servers_scratch(temp), 0);
  EXPECT_EQ(remove_dead_servers_scratch(temp / "missing"), 0);
  fs::remove_all(temp);
}

}  // namespace
}  // namespace bathyslam::server

// Issue 37 fault 2: a write the disk refuses is a WriteError, wherever in the file it happens.
// /dev/full refuses every write with ENOSPC, as a full disk does; the writers that write under
// a temporary name are pointed at it by a link of that name.
#include "core/io/bundle.h"
#include "core/io/file_bytes.h"
#include "core/io/gsf/gsf_writer.h"

#include <gtest/gtest.h>

#include <cerrno>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <vector>

#include <unistd.h>

namespace bathyslam {
namespace {

namespace fs = std::filesystem;

// A fresh folder whose `<name>.partial` leads to /dev/full.
struct FullDisk {
  fs::path dir = fs::temp_directory_path() / ("file_bytes_test_" + std::to_string(getpid()));
  explicit FullDisk(const std::string& name) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    fs::create_symlink("/dev/full", dir / (name + ".partial"));
  }
  ~FullDisk() { fs::remove_all(dir); }
};

void expect_out_of_space(const std::function<void()>& write) {
  try {
    write();
    ADD_FAILURE() << "the write did not throw";
  } catch (const WriteError& error) {
    EXPECT_EQ(error.error_number(), ENOSPC) << error.what();
    EXPECT_TRUE(error.out_of_space());
  }
}

// Small enough to wait in the stream's buffer: only closing the file writes it, and fails.
TEST(WriteError, ABufferedTailTheDiskRefusesAtCloseIsAnError) {
  const std::vector<std::uint8_t> bytes(100, 7);
  expect_out_of_space([&] { write_file_bytes("/dev/full", bytes); });
}

TEST(WriteError, ALargeWriteTheDiskRefusesIsAnError) {
  const std::vector<std::uint8_t> bytes(1 << 20, 7);
  expect_out_of_space([&] { write_file_bytes("/dev/full", bytes); });
}

TEST(WriteError, TheBundleWriterSaysTheDiskIsFull) {
  const FullDisk disk("nav.csv");
  const std::vector<NavSample> nav = {{1720000000.0, 452000.125, 4630000.5, 1.25, 0.5, -0.25, 89.875}};
  expect_out_of_space([&] { write_nav_csv(nav, disk.dir / "nav.csv"); });
  EXPECT_FALSE(fs::exists(disk.dir / "nav.csv"));
}

TEST(WriteError, TheGsfWriterSaysTheDiskIsFull) {
  const FullDisk disk("corrected.gsf");
  expect_out_of_space([&] {
    gsf::Writer writer(disk.dir / "corrected.gsf");
    writer.write(gsf::Comment{1720000000.0, "a comment"});
    writer.close();
  });
  EXPECT_FALSE(fs::exists(disk.dir / "corrected.gsf"));
}

}  // namespace
}  // namespace bathyslam

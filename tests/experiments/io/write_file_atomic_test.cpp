// write_file_atomic: a file that cannot be put in place names the path and the system's reason
// (the hostile pass of 2026-12-06 found `measure --overlay FOLDER` saying only "cannot move the
// finished file into place"), and leaves no temporary behind.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

TEST(WriteFileAtomic, AFolderInTheWayIsNamedWithTheReason) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_write_atomic";
  fs::remove_all(dir);
  fs::create_directories(dir / "a_folder.png" / "inside");
  try {
    write_file_atomic((dir / "a_folder.png").string(), "x");
    FAIL() << "a folder was overwritten";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((dir / "a_folder.png").string()), std::string::npos) << what;
    EXPECT_NE(what.find("directory"), std::string::npos) << what;
  }
  int left = 0;
  for (const auto& entry : fs::directory_iterator(dir)) left += entry.is_regular_file() ? 1 : 0;
  EXPECT_EQ(left, 0) << "a temporary was left behind";
}

}  // namespace
}  // namespace reposetwin::experiments

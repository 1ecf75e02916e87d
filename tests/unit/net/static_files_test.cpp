// The viewer's page folder: read whole at start, and refused, naming the file, where it holds what
// could serve something other than the page (a symbolic link).
#include "net/static_files.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace haptic::net {
namespace {

class StaticFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = std::filesystem::temp_directory_path() / ("static-files-" + std::to_string(::getpid()));
    std::filesystem::remove_all(root_);
    std::filesystem::create_directories(root_ / "vendor");
    std::ofstream(root_ / "index.html") << "<!doctype html>";
    std::ofstream(root_ / "vendor" / "empty.js");  // an empty file is a file
  }
  void TearDown() override { std::filesystem::remove_all(root_); }

  /// The message `load` refuses the folder with.
  std::string refusal() {
    StaticFiles files;
    try {
      files.load(root_, "viewer_root");
    } catch (const std::runtime_error& error) {
      return error.what();
    }
    return {};
  }

  std::filesystem::path root_;
};

TEST_F(StaticFilesTest, ReadsEveryFileOnceAndServesItByItsPath) {
  StaticFiles files;
  files.load(root_, "viewer_root");
  ASSERT_NE(files.find("/"), nullptr);
  EXPECT_EQ(files.find("/")->body, "<!doctype html>");
  ASSERT_NE(files.find("/vendor/empty.js"), nullptr);
  EXPECT_EQ(files.find("/vendor/empty.js")->body, "");
  std::filesystem::remove(root_ / "index.html");  // read at start: later changes do not show
  EXPECT_NE(files.find("/index.html"), nullptr);
  EXPECT_EQ(files.find("/vendor/../index.html"), nullptr);
}

TEST_F(StaticFilesTest, ASymbolicLinkIsRefusedByName) {
  std::filesystem::create_symlink("/etc/hostname", root_ / "vendor" / "outside.js");
  const std::string message = refusal();
  EXPECT_NE(message.find("viewer_root: '" + (root_ / "vendor" / "outside.js").string() +
                         "' is a symbolic link"),
            std::string::npos)
      << message;
}

}  // namespace
}  // namespace haptic::net

// confinePath: everything outside the model directory is refused, symlinks and ".." included.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include "motion_model_estimation/io/path_confinement.h"

namespace {

class Confinement : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/mme_confine_XXXXXX";
    base_ = mkdtemp(tmpl);
    dir_ = base_ + "/models";
    ASSERT_EQ(system(("mkdir -p " + dir_ + "/sub " + base_ + "/outside").c_str()), 0);
    std::ofstream(dir_ + "/a.yaml") << "x";
    std::ofstream(base_ + "/outside/secret.yaml") << "x";
    ASSERT_EQ(symlink((base_ + "/outside/secret.yaml").c_str(), (dir_ + "/link.yaml").c_str()), 0);
    ASSERT_EQ(symlink((base_ + "/outside").c_str(), (dir_ + "/linkdir").c_str()), 0);
  }
  void TearDown() override { ASSERT_EQ(system(("rm -rf " + base_).c_str()), 0); }
  std::string base_, dir_, error_;
};

TEST_F(Confinement, InsidePathsResolve) {
  EXPECT_EQ(mme::confinePath(dir_, "a.yaml", false, &error_), dir_ + "/a.yaml");
  EXPECT_EQ(mme::confinePath(dir_, dir_ + "/a.yaml", false, &error_), dir_ + "/a.yaml");
  EXPECT_EQ(mme::confinePath(dir_, "new.yaml", true, &error_), dir_ + "/new.yaml");
  EXPECT_EQ(mme::confinePath(dir_, "sub/new.yaml", true, &error_), dir_ + "/sub/new.yaml");
  EXPECT_EQ(mme::confinePath(dir_, "sub/../b.yaml", true, &error_), dir_ + "/b.yaml");
}

TEST_F(Confinement, OutsidePathsAreRefusedWithAMessage) {
  for (const std::string& p : {std::string("../outside/secret.yaml"), base_ + "/outside/secret.yaml",
                               std::string("/etc/passwd"), std::string("sub/../../outside/x.yaml"),
                               std::string("link.yaml"), std::string("linkdir/secret.yaml")}) {
    error_.clear();
    EXPECT_EQ(mme::confinePath(dir_, p, false, &error_), "") << p;
    EXPECT_FALSE(error_.empty()) << p;
  }
  for (const std::string& p : {std::string("../x.yaml"), std::string("/tmp/x.yaml"),
                               std::string("link.yaml"), std::string("linkdir/x.yaml"),
                               std::string("missing_dir/x.yaml"), std::string(""),
                               std::string("sub/..")}) {
    error_.clear();
    EXPECT_EQ(mme::confinePath(dir_, p, true, &error_), "") << p;
    EXPECT_FALSE(error_.empty()) << p;
  }
  EXPECT_EQ(mme::confinePath(base_ + "/nope", "a.yaml", true, &error_), "");
}

}  // namespace

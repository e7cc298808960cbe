// rostest: estimator_node with ~select_structure (and so ~sensor_muscles) on a real walk
// (estimator_muscles.test). Pass: ~stats reports muscles=fitted with a muscle count; the model
// ~export_model returns has muscle bond types; the refits of their linear part run (counted in
// ~stats) and the model's 10-frame prediction is reported beside the guesses.
#include "motion_model_estimation/ExportModel.h"
#include "master_check.h"
#include "test_estimator_common.h"

namespace {

using namespace mmetest;

TEST(EstimatorMuscles, AddsSensorMusclesToTheChosenStructureAndRefitsThem) {
  ros::NodeHandle nh;
  StatsWatcher stats(nh);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const auto settled = [](const std::string& l) {
    return l.find(" muscles=fitted") != std::string::npos || l.find(" muscles=not_kept") != std::string::npos ||
           l.find(" muscles=failed") != std::string::npos;
  };
  ASSERT_TRUE(stats.waitFor(settled, 240.0)) << "last ~stats: " << stats.line();
  ASSERT_NE(stats.line().find(" muscles=fitted"), std::string::npos) << stats.line();
  EXPECT_GT(parseStatsLine(stats.line())["muscle_count"], 0.0) << stats.line();

  ASSERT_TRUE(ros::service::waitForService("estimator/export_model", ros::Duration(10.0)));
  motion_model_estimation::ExportModel exported;
  ASSERT_TRUE(ros::service::call("estimator/export_model", exported));
  EXPECT_TRUE(exported.response.success) << exported.response.message;
  EXPECT_NE(exported.response.yaml.find("kind: muscle"), std::string::npos)
      << "the published model has no muscle";

  // The linear part is refitted each period (1 s); the model is judged against the guesses.
  EXPECT_TRUE(stats.waitFor([](const std::string& l) { return parseStatsLine(l)["muscle_refits"] >= 2.0; }, 30.0))
      << stats.line();
  EXPECT_TRUE(stats.waitFor([](const std::string& l) {
    return l.find(" predict10_model_mm=") != std::string::npos &&
           l.find(" predict10_constant_velocity_mm=") != std::string::npos;
  }, 30.0)) << stats.line();
  std::printf("last ~stats: %s\n", stats.line().c_str());
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_estimator_muscles");
  if (!mmetest::masterAnswers()) return 2;
  return RUN_ALL_TESTS();
}

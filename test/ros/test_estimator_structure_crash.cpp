// rostest: estimator_node with ~select_structure on the real 43-marker window that crashed it
// (estimator_structure_crash.test). Pass: the selection ends, chosen (possibly cut by its time
// limit) or failed with its reason in ~stats; afterwards the node is still up: ~stats keeps
// coming, ~export_model answers, and every frame of the stream was accepted.
#include <std_srvs/Trigger.h>

#include "motion_model_estimation/ExportModel.h"
#include "master_check.h"
#include "test_estimator_common.h"

namespace {

using namespace mmetest;

constexpr int kFrames = 100;  // window_0_99.trc

TEST(EstimatorStructureCrash, TheNodeOutlivesTheSelectionOnTheCrashWindow) {
  ros::NodeHandle nh;
  StatsWatcher stats(nh);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const auto ended = [](const std::string& l) {
    return l.find(" structure=chosen:") != std::string::npos || l.find(" structure=failed") != std::string::npos;
  };
  ASSERT_TRUE(stats.waitFor(ended, 150.0)) << "last ~stats: " << stats.line();
  const std::string at_end = stats.line();
  if (at_end.find(" structure=failed") != std::string::npos)
    EXPECT_NE(at_end.find(" structure_error="), std::string::npos) << "a failure says why: " << at_end;
  else
    EXPECT_EQ(parseStatsLine(at_end)["structure_selections"], 1.0) << at_end;

  // Still running: two more ~stats (1 Hz), and the export service answers.
  const int seen = stats.count();
  EXPECT_TRUE(stats.waitFor([&](const std::string&) { return stats.count() >= seen + 2; }, 20.0))
      << "~stats stopped after the selection";
  ASSERT_TRUE(ros::service::waitForService("estimator/export_model", ros::Duration(10.0)));
  motion_model_estimation::ExportModel exported;
  ASSERT_TRUE(ros::service::call("estimator/export_model", exported)) << "the node does not answer";
  EXPECT_FALSE(exported.response.message.empty());

  // No frame lost: the whole stream was accepted.
  EXPECT_TRUE(stats.waitFor([](const std::string& l) { return parseStatsLine(l)["accepted"] == kFrames; }, 20.0))
      << stats.line();
  const std::map<std::string, double> fields = parseStatsLine(stats.line());
  EXPECT_EQ(fields.at("rejected"), 0.0) << stats.line();
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_estimator_structure_crash");
  if (!mmetest::masterAnswers()) return 2;
  return RUN_ALL_TESTS();
}

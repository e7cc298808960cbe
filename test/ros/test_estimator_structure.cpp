// rostest: estimator_node with ~select_structure on a bag of paper_object and a model of its
// particles alone. Pass: ~stats reports structure=chosen:<level> and one selection; ~estimate
// then carries a spring model whose stiffnesses, sorted, are paper_object's within 1 % (the
// chosen types are named s00.., not the scene's, so they are compared as a set); the report CSV
// is in ~model_dir; ~reset says the structure is chosen again, and it is (two selections).
#include <std_srvs/Trigger.h>

#include <fstream>

#include "test_estimator_common.h"
#include "master_check.h"

namespace {

using namespace mmetest;

/// Stiffness values of an estimate ("<type>/stiffness"), sorted.
std::vector<double> stiffnesses(const ModelEstimate& e) {
  std::vector<double> k;
  for (size_t j = 0; j < e.parameter_names.size() && j < e.values.size(); ++j) {
    const std::string& name = e.parameter_names[j];
    if (name.size() > 10 && name.compare(name.size() - 10, 10, "/stiffness") == 0) k.push_back(e.values[j]);
  }
  std::sort(k.begin(), k.end());
  return k;
}

TEST(EstimatorStructure, ChoosesTheStructureIdentifiesItAndChoosesAgainOnReset) {
  ros::NodeHandle nh, pnh("~");
  std::string model_dir;
  ASSERT_TRUE(pnh.getParam("model_dir", model_dir));
  StatsWatcher stats(nh);
  EstimateRecorder recorder(nh, "estimator/estimate");
  ros::AsyncSpinner spinner(2);
  spinner.start();

  ASSERT_TRUE(stats.waitFor([](const std::string& l) { return l.find(" structure=chosen:") != std::string::npos; }, 60.0))
      << "last ~stats: " << stats.line();
  EXPECT_EQ(parseStatsLine(stats.line())["structure_selections"], 1.0) << stats.line();

  // The truth's stiffnesses, sorted.
  const Truth truth = sceneTruth("paper_object");
  std::vector<double> want;
  for (size_t k = 0; k < truth.names.size(); ++k)
    if (truth.names[k].find("/stiffness") != std::string::npos) want.push_back(truth.values[k]);
  std::sort(want.begin(), want.end());
  std::string last;
  const bool found = recorder.waitUntil(
      [&](const std::vector<EstimateRecorder::Entry>& entries) {
        if (entries.empty()) return false;
        const std::vector<double> got = stiffnesses(entries.back().msg);
        std::ostringstream s;
        for (double k : got) s << k << " ";
        last = s.str();
        if (got.size() != want.size()) return false;
        for (size_t k = 0; k < got.size(); ++k)
          if (!(std::fabs(got[k] - want[k]) <= 0.01 * want[k])) return false;
        return true;
      },
      30.0);
  EXPECT_TRUE(found) << "last estimate's stiffnesses: " << last;

  std::ifstream report(model_dir + "/structure_report.csv");
  ASSERT_TRUE(report.good()) << model_dir << "/structure_report.csv";
  std::string header;
  std::getline(report, header);
  EXPECT_EQ(header.rfind("name,bonds,bond_types,parameters,", 0), 0u) << header;

  std_srvs::Trigger reset;
  ASSERT_TRUE(ros::service::waitForService("estimator/reset", ros::Duration(10.0)));
  ASSERT_TRUE(ros::service::call("estimator/reset", reset));
  EXPECT_TRUE(reset.response.success);
  EXPECT_NE(reset.response.message.find("structure"), std::string::npos) << reset.response.message;
  EXPECT_TRUE(stats.waitFor([](const std::string& l) {
    return parseStatsLine(l)["structure_selections"] == 2.0 && l.find(" structure=chosen:") != std::string::npos;
  }, 60.0)) << "last ~stats: " << stats.line();
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_estimator_structure");
  if (!mmetest::masterAnswers()) return 2;
  return RUN_ALL_TESTS();
}

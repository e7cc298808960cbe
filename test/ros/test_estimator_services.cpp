// rostest: estimator_node's services on a live paper_object stream (simulator_node).
//   ~export_model  empty path: the YAML only; a path inside ~model_dir: the same YAML written
//                  there (reloads to the same values, bit for bit); a path outside it or in a
//                  missing directory: success false + a message, and the node goes on.
//   ~reset         the population restarts: a later estimate has a lower generation.
//   ~load_model    a model with only the stiffnesses free replaces the model (the estimates'
//                  parameter_names follow and converge); bad paths and a broken file: success
//                  false + a message, the loaded model stays.
// The tests run in declaration order and share the node; each one waits for what it needs.
#include <std_srvs/Trigger.h>
#include <yaml-cpp/yaml.h>

#include <sys/stat.h>

#include <cstdio>
#include <fstream>
#include <iterator>

#include "motion_model_estimation/ExportModel.h"
#include "motion_model_estimation/LoadModel.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "test_estimator_common.h"
#include "master_check.h"

namespace {

using namespace mmetest;
using motion_model_estimation::ExportModel;
using motion_model_estimation::LoadModel;

constexpr double kTolerance = 0.01;      // relative, every parameter vs the truth
constexpr double kConvergeTimeoutS = 25.0;

struct Context {
  std::unique_ptr<EstimateRecorder> recorder;
  Truth truth;
  std::string model_dir;
};
Context* g = nullptr;

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}
bool exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

/// The free parameters of a model as name -> value, in canonical order.
std::vector<std::pair<std::string, double>> freeValues(const mme::Model& m) {
  std::vector<std::pair<std::string, double>> out;
  for (const mme::ParamRef& ref : mme::freeParameters(m)) out.emplace_back(ref.name, mme::getParam(m, ref));
  return out;
}

bool callExport(const std::string& path, ExportModel::Response* res) {
  ExportModel srv;
  srv.request.path = path;
  const bool ok = ros::service::call("estimator/export_model", srv);
  *res = srv.response;
  return ok;
}
bool callLoad(const std::string& path, LoadModel::Response* res) {
  LoadModel srv;
  srv.request.path = path;
  const bool ok = ros::service::call("estimator/load_model", srv);
  *res = srv.response;
  return ok;
}

TEST(EstimatorServices, AdvertisedAndConverging) {
  for (const char* s : {"estimator/reset", "estimator/export_model", "estimator/load_model"})
    ASSERT_TRUE(ros::service::waitForService(s, ros::Duration(15.0))) << s;
  std::string report = "no estimate";
  ASSERT_GE(waitForConvergence(*g->recorder, g->truth, kTolerance, kConvergeTimeoutS, 3, &report,
                               0, 100),
            0)
      << report;
}

TEST(EstimatorServices, ExportWithoutPathReturnsTheCurrentModel) {
  EstimateRecorder::Entry before;
  ASSERT_TRUE(g->recorder->last(&before));
  ExportModel::Response res;
  ASSERT_TRUE(callExport("", &res));
  ASSERT_TRUE(res.success) << res.message;
  ASSERT_FALSE(res.yaml.empty());
  mme::Model exported;
  ASSERT_NO_THROW(exported = mme::loadModelString(res.yaml, "export")) << res.yaml;
  const auto values = freeValues(exported);
  ASSERT_EQ(values.size(), g->truth.names.size());
  ASSERT_EQ(before.msg.values.size(), g->truth.names.size());
  for (size_t k = 0; k < values.size(); ++k) {
    EXPECT_EQ(values[k].first, g->truth.names[k]);
    // Converged before the call: within the tolerance of the truth and of the last estimate.
    EXPECT_NEAR(values[k].second, g->truth.values[k], kTolerance * std::fabs(g->truth.values[k]))
        << values[k].first;
    EXPECT_NEAR(values[k].second, before.msg.values[k], kTolerance * std::fabs(g->truth.values[k]))
        << values[k].first;
  }
  // SPEC section 4: a std per free parameter and an identification block that is not older
  // than the last estimate seen before the call.
  const YAML::Node root = YAML::Load(res.yaml);
  ASSERT_TRUE(root["identification"].IsMap()) << res.yaml;
  EXPECT_GE(root["identification"]["generations"].as<uint32_t>(), before.msg.generation);
  EXPECT_EQ(root["identification"]["frames"].as<int>(), 100);
  size_t with_std = 0;
  for (const YAML::Node& type : root["bond_types"])
    for (const char* key : {"stiffness", "rest_length"})
      if (type[key] && type[key]["std"]) ++with_std;
  EXPECT_EQ(with_std, g->truth.names.size());
}

TEST(EstimatorServices, ExportToAPathWritesTheSameYamlThatReloadsBitForBit) {
  for (const std::string& path :
       {std::string("exported.yaml"), g->model_dir + "/exported_absolute.yaml"}) {
    const std::string file = path[0] == '/' ? path : g->model_dir + "/" + path;
    std::remove(file.c_str());
    ExportModel::Response res;
    ASSERT_TRUE(callExport(path, &res));
    ASSERT_TRUE(res.success) << path << ": " << res.message;
    EXPECT_NE(res.message.find(file.substr(file.rfind('/') + 1)), std::string::npos)
        << res.message;
    ASSERT_TRUE(exists(file)) << file;
    EXPECT_EQ(readFile(file), res.yaml);
    const auto from_file = freeValues(mme::loadModelFile(file));
    const auto from_reply = freeValues(mme::loadModelString(res.yaml, "reply"));
    ASSERT_EQ(from_file.size(), g->truth.names.size());
    ASSERT_EQ(from_file.size(), from_reply.size());
    for (size_t k = 0; k < from_file.size(); ++k) {
      EXPECT_EQ(from_file[k].first, from_reply[k].first);
      EXPECT_EQ(from_file[k].second, from_reply[k].second) << from_file[k].first;  // exact
      EXPECT_NEAR(from_file[k].second, g->truth.values[k],
                  kTolerance * std::fabs(g->truth.values[k]))
          << from_file[k].first;
    }
  }
}

TEST(EstimatorServices, ExportToAnUnwritablePathFailsAndTheNodeGoesOn) {
  for (const std::string& path :
       {std::string("/nonexistent_dir/x.yaml"), std::string("../outside_model_dir.yaml"),
        std::string("no_such_subdir/x.yaml")}) {
    ExportModel::Response res;
    const ros::WallTime t0 = ros::WallTime::now();
    ASSERT_TRUE(callExport(path, &res)) << "the call itself succeeds: " << path;
    std::printf("[ INFO     ] export '%s': %.3f s: %s\n", path.c_str(),
                (ros::WallTime::now() - t0).toSec(), res.message.c_str());
    EXPECT_FALSE(res.success) << path;
    EXPECT_FALSE(res.message.empty()) << path;
  }
  EXPECT_FALSE(exists("/nonexistent_dir/x.yaml"));
  EXPECT_FALSE(exists(g->model_dir + "/../outside_model_dir.yaml"));
  // Still alive: a later call works and estimates keep coming.
  ExportModel::Response res;
  ASSERT_TRUE(callExport("", &res));
  EXPECT_TRUE(res.success) << res.message;
  const size_t n = g->recorder->count();
  EXPECT_TRUE(g->recorder->waitUntil([&](const auto& e) { return e.size() >= n + 3; }, 10.0));
}

TEST(EstimatorServices, ResetRestartsThePopulation) {
  EstimateRecorder::Entry before;
  ASSERT_TRUE(g->recorder->last(&before));
  ASSERT_GT(before.msg.generation, 20u);
  std_srvs::Trigger srv;
  ASSERT_TRUE(ros::service::call("estimator/reset", srv));
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  const size_t after = g->recorder->count();
  // An estimate with a lower generation than any before the reset: a new population.
  EXPECT_TRUE(g->recorder->waitUntil(
      [&](const std::vector<EstimateRecorder::Entry>& e) {
        for (size_t k = after; k < e.size(); ++k)
          if (e[k].msg.generation < before.msg.generation) return true;
        return false;
      },
      10.0))
      << "no estimate with a generation below " << before.msg.generation << " after ~reset";
  // And identification goes on from there (generations grow again).
  EXPECT_TRUE(g->recorder->waitUntil(
      [&](const std::vector<EstimateRecorder::Entry>& e) {
        uint32_t lowest = before.msg.generation;
        for (size_t k = after; k < e.size(); ++k) {
          if (e[k].msg.generation < lowest) lowest = e[k].msg.generation;
          else if (lowest < before.msg.generation && e[k].msg.generation > lowest) return true;
        }
        return false;
      },
      10.0));
}

TEST(EstimatorServices, LoadModelReplacesTheModel) {
  // paper_object with the rest lengths fixed at their true values: 10 free stiffnesses.
  mme::Model model = mme::makeScene("paper_object").model;
  std::vector<std::string> stiffnesses;
  for (mme::BondType& t : model.bond_types) {
    t.param(mme::kRestLength).free = false;
    t.param(mme::kStiffness).free = true;
    t.param(mme::kStiffness).has_value = false;  // as in config/models: no initial value
    stiffnesses.push_back(t.name + "/stiffness");
  }
  ASSERT_EQ(stiffnesses.size(), 10u);
  mme::writeModelFile(g->model_dir + "/stiffness_only.yaml", model);
  const size_t before = g->recorder->count();
  LoadModel::Response res;
  ASSERT_TRUE(callLoad("stiffness_only.yaml", &res));
  ASSERT_TRUE(res.success) << res.message;
  // Estimates of the new parameter set arrive and converge to the truth of those parameters.
  Truth truth;
  for (const std::string& name : stiffnesses) {
    truth.names.push_back(name);
    truth.values.push_back(g->truth.at(name));
  }
  std::string report = "no estimate";
  const long first = waitForConvergence(*g->recorder, truth, kTolerance, kConvergeTimeoutS, 3,
                                        &report, before);
  ASSERT_GE(first, 0) << report;
  EstimateRecorder::Entry last;
  ASSERT_TRUE(g->recorder->last(&last));
  EXPECT_EQ(last.msg.parameter_names, stiffnesses);
  EXPECT_EQ(last.msg.values.size(), stiffnesses.size());
}

TEST(EstimatorServices, LoadModelRefusesBadPathsAndKeepsTheModel) {
  {
    std::ofstream broken(g->model_dir + "/broken.yaml");
    broken << "particles:\n  - {name: a, mass: -1}\n";
  }
  for (const std::string& path :
       {std::string("does_not_exist.yaml"), std::string("/nonexistent_dir/x.yaml"),
        std::string("../outside.yaml"), std::string("broken.yaml"), std::string("")}) {
    LoadModel::Response res;
    ASSERT_TRUE(callLoad(path, &res)) << "the call itself succeeds: " << path;
    EXPECT_FALSE(res.success) << "'" << path << "'";
    EXPECT_FALSE(res.message.empty()) << "'" << path << "'";
  }
  // The loaded model (10 stiffnesses) stays, and estimates keep coming.
  const size_t n = g->recorder->count();
  ASSERT_TRUE(g->recorder->waitUntil([&](const auto& e) { return e.size() >= n + 3; }, 10.0));
  for (const EstimateRecorder::Entry& e : g->recorder->since(n))
    EXPECT_EQ(e.msg.parameter_names.size(), 10u);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_estimator_services");
  if (!mmetest::masterAnswers()) return 2;
  ros::NodeHandle nh, pnh("~");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  Context context;
  g = &context;
  if (!pnh.getParam("model_dir", context.model_dir) || context.model_dir.empty()) {
    std::fprintf(stderr, "~model_dir (the estimator's ~model_dir) is required\n");
    return 1;
  }
  context.truth = sceneTruth("paper_object");
  context.recorder = std::make_unique<EstimateRecorder>(nh, "estimator/estimate");
  const int rc = RUN_ALL_TESTS();
  context.recorder.reset();
  spinner.stop();
  return rc;
}

// estimator_node's options without a ROS master (live/estimator_node_options.h): the documented
// defaults, every check naming the parameter it refuses, the preset and what overrides it, and
// a parameter of the wrong type refused by name.
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <variant>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/live/estimator_node_options.h"

namespace {

/// Parameters as a map; a value of another type than asked for is "the wrong type", as on the
/// parameter server.
class MapSource : public mme::ParameterSource {
 public:
  using Value = std::variant<std::string, double, int, bool>;
  std::map<std::string, Value> values;

  bool get(const std::string& name, std::string* v) const override { return read(name, v); }
  bool get(const std::string& name, double* v) const override {
    const auto it = values.find(name);
    if (it != values.end() && std::holds_alternative<int>(it->second)) {  // as XmlRpc does
      *v = std::get<int>(it->second);
      return true;
    }
    return read(name, v);
  }
  bool get(const std::string& name, int* v) const override { return read(name, v); }
  bool get(const std::string& name, bool* v) const override { return read(name, v); }

 private:
  template <typename T>
  bool read(const std::string& name, T* v) const {
    const auto it = values.find(name);
    if (it == values.end()) return false;
    if (!std::holds_alternative<T>(it->second)) throw mme::InputError("~" + name + " has the wrong type");
    *v = std::get<T>(it->second);
    return true;
  }
};

MapSource withModel() {
  MapSource s;
  s.values["model"] = std::string("m.yaml");
  s.values["model_dir"] = std::string("/tmp/models");
  return s;
}

/// The InputError's message for `source`, or "" when the options are accepted.
std::string refusal(const MapSource& source) {
  try {
    mme::readEstimatorNodeOptions(source);
  } catch (const mme::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(EstimatorNodeOptions, DefaultsAreTheDocumentedOnes) {
  const mme::EstimatorNodeOptions o = mme::readEstimatorNodeOptions(withModel());
  EXPECT_EQ(o.model_path, "m.yaml");
  EXPECT_EQ(o.input_type, mme::InputType::kMarkers);
  EXPECT_EQ(o.update_rate_hz, 20.0);
  EXPECT_EQ(o.structure_max_time_s, 120.0);
  EXPECT_EQ(o.background_nice, 10);
  EXPECT_FALSE(o.select_structure);
  EXPECT_EQ(o.model_dir, "/tmp/models");
  EXPECT_EQ(o.estimator.es.offspring, o.estimator.es.population);
  EXPECT_LE(o.estimator.min_frames, o.estimator.window_frames);
}

TEST(EstimatorNodeOptions, EveryCheckNamesItsParameter) {
  EXPECT_EQ(refusal(MapSource()), "~model is required (path to a model file)");
  struct Case {
    const char* name;
    MapSource::Value value;
    const char* message;
  };
  const Case cases[] = {
      {"input_type", std::string("lidar"), "~input_type must be markers, pointcloud or vicon, got 'lidar'"},
      {"bag_rate", -1.0, "~bag_rate must be >= 0"},
      {"update_rate_hz", 0.0, "~update_rate_hz must be in (0, 1000]"},
      {"color_bonds_by", std::string("mood"), "~color_bonds_by must be strain or local_cost"},
      {"particle_diameter_m", 0.0, "~particle_diameter_m must be > 0"},
      {"autosave_period_sec", 0.0, "~autosave_period_sec must be > 0"},
      {"structure_report_path", std::string(""), "~structure_report_path must not be empty"},
      {"structure_max_time_sec", -1.0, "~structure_max_time_sec must be >= 0 (0 = no limit)"},
      {"window_frames", 2, "~window_frames must be >= 3"},
      {"min_frames", 2, "~min_frames must be in [3, ~window_frames]"},
      {"population", 1, "~population must be >= 2"},
      {"seed", -1, "~seed must be >= 0"},
      {"threads", 0, "~threads must be in [1, 256]"},
      {"preset", std::string("fast"), "~preset must be default or paper, got 'fast'"},
      {"cost", std::string("l1"), "~cost must be auto, short_term or output_error, got 'l1'"},
      {"refine_period", -1, "~refine_start_generation and ~refine_period must be >= 0"},
      {"background_nice", -1, "~background_nice must be in [0, 19]"},
      {"background_nice", 20, "~background_nice must be in [0, 19]"},
  };
  for (const Case& c : cases) {
    MapSource s = withModel();
    s.values[c.name] = c.value;
    EXPECT_EQ(refusal(s), c.message) << c.name;
  }
}

TEST(EstimatorNodeOptions, StructureSelectionNeedsALongEnoughWindow) {
  MapSource s = withModel();
  s.values["select_structure"] = true;
  s.values["window_frames"] = 30;
  EXPECT_EQ(refusal(s), "~select_structure needs ~window_frames >= 35 (20 frames fitted, 15 held out)");
  s.values["window_frames"] = 40;
  EXPECT_EQ(refusal(s), "");
}

// ~sensor_muscles: on by default with ~select_structure only, either way on request; its own
// parameters are checked when it is on.
TEST(EstimatorNodeOptions, SensorMusclesFollowStructureSelectionAndTheirParametersAreChecked) {
  MapSource s = withModel();
  EXPECT_FALSE(mme::readEstimatorNodeOptions(s).sensor_muscles);
  s.values["select_structure"] = true;
  mme::EstimatorNodeOptions o = mme::readEstimatorNodeOptions(s);
  EXPECT_TRUE(o.sensor_muscles);
  EXPECT_EQ(o.muscles.min_frames, o.estimator.window_frames);
  EXPECT_EQ(o.muscles.refit_period_s, 1.0);
  EXPECT_EQ(o.muscles.fit.sensors, 6);
  EXPECT_EQ(o.muscles.fit.max_time_s, 20.0);
  s.values["sensor_muscles"] = false;
  EXPECT_FALSE(mme::readEstimatorNodeOptions(s).sensor_muscles);
  s = withModel();
  s.values["sensor_muscles"] = true;  // a passive model given: muscles on request
  EXPECT_TRUE(mme::readEstimatorNodeOptions(s).sensor_muscles);
  s.values["window_frames"] = 30;
  EXPECT_EQ(refusal(s), "~sensor_muscles needs ~window_frames >= 35 (the fit holds its last 20 % out)");
  const std::pair<const char*, MapSource::Value> bad[] = {
      {"muscle_sensors", 0}, {"muscles_max_time_sec", -1.0}, {"muscle_refit_period_sec", -0.5}};
  for (const auto& [name, value] : bad) {
    MapSource b = withModel();
    b.values["sensor_muscles"] = true;
    b.values[name] = value;
    EXPECT_EQ(refusal(b).rfind(std::string("~") + name, 0), 0u) << refusal(b);
  }
}

// ~estimate_values: on by default; off shows the model as it is, which excludes choosing a
// structure.
TEST(EstimatorNodeOptions, EstimateValuesOffShowsTheModelAndExcludesStructureSelection) {
  MapSource s = withModel();
  EXPECT_TRUE(mme::readEstimatorNodeOptions(s).estimator.estimate_values);
  s.values["estimate_values"] = false;
  EXPECT_FALSE(mme::readEstimatorNodeOptions(s).estimator.estimate_values);
  s.values["select_structure"] = true;
  EXPECT_EQ(refusal(s), "~estimate_values false shows the model as it is: it cannot be combined with "
                        "~select_structure");
}

TEST(EstimatorNodeOptions, ThePaperPresetAndWhatOverridesIt) {
  MapSource s = withModel();
  s.values["preset"] = std::string("paper");
  const mme::EstimatorNodeOptions paper = mme::readEstimatorNodeOptions(s);
  EXPECT_EQ(paper.estimator.cost, mme::CostChoice::kShortTerm);
  EXPECT_EQ(paper.estimator.es.refine_algorithm, mme::RefineAlgorithm::kBobyqa);
  s.values["cost"] = std::string("output_error");
  s.values["refine_algorithm"] = std::string("levenberg_marquardt");
  const mme::EstimatorNodeOptions overridden = mme::readEstimatorNodeOptions(s);
  EXPECT_EQ(overridden.estimator.cost, mme::CostChoice::kOutputError);
  EXPECT_EQ(overridden.estimator.es.refine_algorithm, mme::RefineAlgorithm::kLevenbergMarquardt);
}

TEST(EstimatorNodeOptions, AParameterOfTheWrongTypeIsRefusedByName) {
  MapSource s = withModel();
  s.values["window_frames"] = std::string("many");
  EXPECT_EQ(refusal(s), "~window_frames has the wrong type");
}

}  // namespace

namespace {

// The island model: off by default; ~islands/enabled or a ~migration_topic alone turns it on,
// an explicit ~islands/enabled false wins; every bad value is refused naming its parameter.
TEST(EstimatorNodeOptions, IslandsAreOffByDefaultAndCheckedWhenOn) {
  const mme::EstimatorNodeOptions defaults = mme::readEstimatorNodeOptions(withModel());
  EXPECT_FALSE(defaults.islands.enabled);
  EXPECT_EQ(defaults.islands.migration_topic, "/mme/migrants");
  EXPECT_EQ(defaults.islands.migration_period_generations, 10);
  EXPECT_EQ(defaults.islands.migrants, 3);
  EXPECT_EQ(defaults.estimator.migrant_queue_batches, 8);

  MapSource on = withModel();
  on.values["islands/enabled"] = true;
  EXPECT_TRUE(mme::readEstimatorNodeOptions(on).islands.enabled);
  MapSource by_topic = withModel();
  by_topic.values["migration_topic"] = std::string("/lab/migrants");
  EXPECT_TRUE(mme::readEstimatorNodeOptions(by_topic).islands.enabled);
  by_topic.values["islands/enabled"] = false;
  EXPECT_FALSE(mme::readEstimatorNodeOptions(by_topic).islands.enabled);

  struct Case {
    const char* name;
    MapSource::Value value;
    const char* message;
  };
  const Case cases[] = {
      {"migration_topic", std::string(""), "~migration_topic must not be empty"},
      {"migration_topic", std::string("/mme/mi grants"), "~migration_topic '/mme/mi grants' is not a topic name"},
      {"migration_topic", std::string("/9lives"), "is not a topic name"},
      {"island_id", std::string("a b"), "~island_id must not contain spaces"},
      {"migration_period_generations", 0, "~migration_period_generations must be >= 1"},
      {"migrants", 0, "~migrants must be in [1, ~population]"},
      {"migrants", 100000, "~migrants must be in [1, ~population]"},
      {"migrant_queue_batches", 0, "~migrant_queue_batches must be >= 1"},
      {"estimate_values", false, "cannot be combined with ~estimate_values false"},
  };
  for (const Case& c : cases) {
    MapSource s = on;
    s.values[c.name] = c.value;
    const std::string why = refusal(s);
    EXPECT_NE(why.find(c.message), std::string::npos) << c.name << ": " << why;
  }
  MapSource wrong_type = on;
  wrong_type.values["migrants"] = std::string("three");
  EXPECT_NE(refusal(wrong_type).find("~migrants"), std::string::npos);
}

}  // namespace

#include "motion_model_estimation/live/estimator_node_options.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>

#include "motion_model_estimation/core/error.h"

namespace mme {

namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw InputError(message);
}

}  // namespace

MuscleJobOptions defaultMuscleJobOptions() {
  MuscleJobOptions o;
  o.fit = liveSensorMuscleOptions();
  o.refit_period_s = 1.0;
  return o;
}

bool parseInputType(const std::string& text, InputType* type) {
  if (text == "markers") {
    *type = InputType::kMarkers;
  } else if (text == "pointcloud") {
    *type = InputType::kPointCloud;
  } else if (text == "vicon") {
    *type = InputType::kVicon;
  } else {
    return false;
  }
  return true;
}

const char* inputTypeName(InputType type) {
  switch (type) {
    case InputType::kMarkers: return "markers";
    case InputType::kPointCloud: return "pointcloud";
    case InputType::kVicon: return "vicon";
  }
  return "?";
}

namespace {

/// The model, the input and how it is shown.
void readInputAndDisplay(const ParameterSource& params, EstimatorNodeOptions* options) {
  EstimatorNodeOptions& o = *options;
  params.get("model", &o.model_path);
  require(!o.model_path.empty(), "~model is required (path to a model file)");
  std::string input_type = inputTypeName(o.input_type);
  params.get("input_type", &input_type);
  require(parseInputType(input_type, &o.input_type),
          "~input_type must be markers, pointcloud or vicon, got '" + input_type + "'");
  params.get("bag", &o.bag);
  params.get("bag_topic", &o.bag_topic);
  params.get("bag_rate", &o.bag_rate);
  require(o.bag_rate >= 0.0 && std::isfinite(o.bag_rate), "~bag_rate must be >= 0");
  params.get("fixed_frame", &o.fixed_frame);
  params.get("update_rate_hz", &o.update_rate_hz);
  require(o.update_rate_hz > 0.0 && o.update_rate_hz <= 1000.0,
          "~update_rate_hz must be in (0, 1000]");
  params.get("publish_markers", &o.publish_markers);
  std::string color_bonds_by = bondColouringName(o.color_bonds_by);
  params.get("color_bonds_by", &color_bonds_by);
  require(parseBondColouring(color_bonds_by, &o.color_bonds_by),
          "~color_bonds_by must be strain or local_cost");
  params.get("particle_diameter_m", &o.particle_diameter_m);
  require(o.particle_diameter_m > 0.0, "~particle_diameter_m must be > 0");
  params.get("tf_timeout_sec", &o.tf_timeout_sec);
  require(o.tf_timeout_sec >= 0.0, "~tf_timeout_sec must be >= 0");
  params.get("vicon_qualify_with_subject", &o.vicon_qualify_with_subject);
}

/// Files (model_dir, autosave, resume, the structure report) and the structure job.
void readFilesAndStructure(const ParameterSource& params, EstimatorNodeOptions* options) {
  EstimatorNodeOptions& o = *options;
  params.get("model_dir", &o.model_dir);
  if (o.model_dir.empty()) {
    const char* ros_home = std::getenv("ROS_HOME");
    const char* home = std::getenv("HOME");
    o.model_dir = ros_home ? ros_home : std::string(home ? home : "/tmp") + "/.ros";
  }
  params.get("autosave_path", &o.autosave_path);
  params.get("autosave_period_sec", &o.autosave_period_sec);
  require(o.autosave_period_sec > 0.0 && std::isfinite(o.autosave_period_sec),
          "~autosave_period_sec must be > 0");
  params.get("initial_model", &o.initial_model);
  params.get("select_structure", &o.select_structure);
  params.get("estimate_values", &o.estimator.estimate_values);
  require(o.estimator.estimate_values || !o.select_structure,
          "~estimate_values false shows the model as it is: it cannot be combined with "
          "~select_structure");
  params.get("structure_report_path", &o.structure_report_path);
  require(!o.structure_report_path.empty(), "~structure_report_path must not be empty");
  params.get("structure_max_time_sec", &o.structure_max_time_s);
  require(o.structure_max_time_s >= 0.0 && std::isfinite(o.structure_max_time_s),
          "~structure_max_time_sec must be >= 0 (0 = no limit)");
  o.sensor_muscles = o.select_structure;
  params.get("sensor_muscles", &o.sensor_muscles);
  params.get("muscle_sensors", &o.muscles.fit.sensors);
  params.get("muscles_max_time_sec", &o.muscles.fit.max_time_s);
  params.get("muscle_refit_period_sec", &o.muscles.refit_period_s);
  params.get("prediction_period_sec", &o.prediction_period_sec);
  require(o.prediction_period_sec >= 0.0 && std::isfinite(o.prediction_period_sec),
          "~prediction_period_sec must be >= 0 (0 = off)");
}

/// The sliding window and the engine's budget per update.
void readWindow(const ParameterSource& params, EstimatorNodeOptions* options) {
  EstimatorNodeOptions& o = *options;
  OnlineEstimatorOptions& e = o.estimator;
  params.get("window_frames", &e.window_frames);
  require(e.window_frames >= 3, "~window_frames must be >= 3");
  require(!o.select_structure || e.window_frames >= 35,
          "~select_structure needs ~window_frames >= 35 (20 frames fitted, 15 held out)");
  require(!o.sensor_muscles || e.window_frames >= 35,
          "~sensor_muscles needs ~window_frames >= 35 (the fit holds its last 20 % out)");
  o.muscles.min_frames = std::max(35, e.window_frames);
  if (o.sensor_muscles) {
    const std::string bad = validateOptions(o.muscles);
    require(bad.empty(), "~" + bad);
  }
  e.min_frames = std::min(e.min_frames, e.window_frames);
  params.get("min_frames", &e.min_frames);
  require(e.min_frames >= 3 && e.min_frames <= e.window_frames,
          "~min_frames must be in [3, ~window_frames]");
  params.get("generations_per_update", &e.generations_per_update);
  require(e.generations_per_update >= 1, "~generations_per_update must be >= 1");
  params.get("update_budget_sec", &e.update_budget_s);
  require(e.update_budget_s > 0.0 && std::isfinite(e.update_budget_s),
          "~update_budget_sec must be > 0");
  params.get("refine_max_sec", &e.refine_max_s);
  require(e.refine_max_s > 0.0 && std::isfinite(e.refine_max_s), "~refine_max_sec must be > 0");
  params.get("background_nice", &o.background_nice);
  require(o.background_nice >= 0 && o.background_nice <= 19, "~background_nice must be in [0, 19]");
  params.get("segment_frames", &e.output_error.segment_frames);
  require(e.output_error.segment_frames >= 2, "~segment_frames must be >= 2");
  params.get("grow_segments", &e.output_error.grow_segments);
  require(e.output_error.grow_segments >= 0, "~grow_segments must be >= 0 (0 = off)");
}

/// The search: population, seed, threads, the preset and what overrides it, the cost.
void readSearch(const ParameterSource& params, OnlineEstimatorOptions* estimator) {
  OnlineEstimatorOptions& e = *estimator;
  params.get("population", &e.es.population);
  require(e.es.population >= 2, "~population must be >= 2");
  e.es.offspring = e.es.population;
  int seed = static_cast<int>(e.es.seed);
  params.get("seed", &seed);
  require(seed >= 0, "~seed must be >= 0");
  e.es.seed = static_cast<uint64_t>(seed);
  params.get("threads", &e.es.threads);
  require(e.es.threads >= 1 && e.es.threads <= 256, "~threads must be in [1, 256]");
  // ~preset chooses the engine settings (default: the measured best; paper: the paper's
  // schedule); the ~refine_* parameters, when set, override it.
  std::string preset_name = presetName(Preset::kDefault);
  params.get("preset", &preset_name);
  Preset preset = Preset::kDefault;
  require(parsePreset(preset_name, &preset),
          "~preset must be " + std::string(presetNames()) + ", got '" + preset_name + "'");
  {
    const EsOptions from_preset = onlineEsOptions(preset);
    e.es.refine_algorithm = from_preset.refine_algorithm;
    e.es.refine_start_generation = from_preset.refine_start_generation;
    e.es.refine_period = from_preset.refine_period;
    e.es.refine_smooth_genes_only = from_preset.refine_smooth_genes_only;
  }
  params.get("refine_start_generation", &e.es.refine_start_generation);
  params.get("refine_period", &e.es.refine_period);
  std::string refine_algorithm = refineAlgorithmName(e.es.refine_algorithm);
  params.get("refine_algorithm", &refine_algorithm);
  require(parseRefineAlgorithm(refine_algorithm, &e.es.refine_algorithm),
          "~refine_algorithm must be " + std::string(refineAlgorithmNames()) + ", got '" +
              refine_algorithm + "'");
  require(e.es.refine_start_generation >= 0 && e.es.refine_period >= 0,
          "~refine_start_generation and ~refine_period must be >= 0");
  if (preset == Preset::kPaper) e.cost = CostChoice::kShortTerm;  // the paper's own cost
  std::string cost = costChoiceName(e.cost);
  params.get("cost", &cost);
  require(parseCostChoice(cost, &e.cost),
          "~cost must be auto, short_term or output_error, got '" + cost + "'");
}

/// A graph resource name as ROS accepts it: '/'-separated names of letters, digits and '_',
/// each starting with a letter (a leading '~' makes it private).
bool isTopicName(const std::string& name) {
  size_t i = !name.empty() && name[0] == '~' ? 1 : 0;
  if (i == name.size()) return false;
  bool segment_start = true;
  for (; i < name.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(name[i]);
    if (c == '/') {
      if (i > 0 && name[i - 1] == '/') return false;
      segment_start = true;
    } else if (segment_start) {
      if (!std::isalpha(c)) return false;
      segment_start = false;
    } else if (!std::isalnum(c) && c != '_') {
      return false;
    }
  }
  return !segment_start;  // not ending with '/'
}

/// The island model (~islands/enabled, ~island_id, ~migration_*, ~migrants); after readSearch,
/// which sets the population the migrants are taken from.
void readIslands(const ParameterSource& params, EstimatorNodeOptions* options) {
  IslandLinkOptions& o = options->islands;
  std::string topic;
  const bool topic_set = params.get("migration_topic", &topic);
  if (topic_set) o.migration_topic = topic;
  o.enabled = topic_set && !topic.empty();  // a topic alone turns migration on...
  params.get("islands/enabled", &o.enabled);  // ...unless ~islands/enabled says otherwise
  params.get("island_id", &o.island_id);
  params.get("migration_period_generations", &o.migration_period_generations);
  params.get("migrants", &o.migrants);
  params.get("migrant_queue_batches", &options->estimator.migrant_queue_batches);
  require(options->estimator.migrant_queue_batches >= 1, "~migrant_queue_batches must be >= 1");
  if (!o.enabled) return;
  require(!o.migration_topic.empty(),
          "~migration_topic must not be empty with ~islands/enabled true (default /mme/migrants)");
  require(isTopicName(o.migration_topic),
          "~migration_topic '" + o.migration_topic +
              "' is not a topic name (letters, digits, '_' and '/'; e.g. /mme/migrants)");
  require(o.island_id.find_first_of(" \t\r\n") == std::string::npos,
          "~island_id must not contain spaces, got '" + o.island_id + "'");
  require(o.migration_period_generations >= 1, "~migration_period_generations must be >= 1");
  require(o.migrants >= 1 && o.migrants <= options->estimator.es.population,
          "~migrants must be in [1, ~population] (" +
              std::to_string(options->estimator.es.population) + "), got " + std::to_string(o.migrants));
  require(options->estimator.estimate_values,
          "~islands/enabled needs a search: it cannot be combined with ~estimate_values false");
}

}  // namespace

EstimatorNodeOptions readEstimatorNodeOptions(const ParameterSource& params) {
  EstimatorNodeOptions o;
  readInputAndDisplay(params, &o);
  readFilesAndStructure(params, &o);
  readWindow(params, &o);
  readSearch(params, &o.estimator);
  readIslands(params, &o);
  const std::string bad = validateOptions(o.estimator);
  require(bad.empty(), "~" + bad);  // its messages name the option, i.e. the parameter
  return o;
}

}  // namespace mme

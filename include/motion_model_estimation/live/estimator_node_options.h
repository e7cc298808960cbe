// The options of estimator_node and the rules they obey, without ROS: every private parameter's
// name, default and check in one place, read from any source of named values. The node reads
// them from the parameter server (ros/estimator_node.cpp); the tests from a map, so that every
// rule is tested without a ROS master. Meaning and units: config/estimator.yaml, docs/node.md.
#pragma once

#include <string>

#include "motion_model_estimation/identification/online/online_estimator.h"
#include "motion_model_estimation/live/muscle_job.h"
#include "motion_model_estimation/live/prediction_monitor.h"
#include "motion_model_estimation/live/visualisation_snapshot.h"

namespace mme {

/// The node's muscle job defaults (liveSensorMuscleOptions, a refit every second).
MuscleJobOptions defaultMuscleJobOptions();

/// What arrives on `markers` (~input_type).
enum class InputType {
  kMarkers,     ///< motion_model_estimation/MarkerFrame
  kPointCloud,  ///< sensor_msgs/PointCloud2, points in particle order, NaN = occluded
  kVicon,       ///< vicon_bridge/Markers (millimetres), received as a ShapeShifter
};

/// The island model: estimators with their own seeds on the same stream exchange their best
/// individuals on one shared topic (docs/node.md, "Islands"). Off unless ~islands/enabled is true,
/// or ~migration_topic is set non-empty and ~islands/enabled is not set.
struct IslandLinkOptions {
  bool enabled = false;
  std::string island_id;                           ///< "" = the node's name (filled by the node)
  std::string migration_topic = "/mme/migrants";   ///< shared by every island (absolute)
  int migration_period_generations = 10;           ///< generations between two emigrations
  int migrants = 3;                                ///< individuals per emigration (the best)
};

/// ROS-side options (see config/estimator.yaml for meaning, units and defaults).
struct EstimatorNodeOptions {
  std::string model_path;
  InputType input_type = InputType::kMarkers;
  std::string bag;                     ///< read this bag (or .trc/.c3d capture) instead of subscribing
  std::string bag_topic;               ///< MarkerFrame topic in the bag ("" = the only one)
  double bag_rate = 0.0;               ///< x real time; 0 = as fast as the estimator keeps up
  std::string fixed_frame;             ///< "" = the model's frame_id
  double update_rate_hz = 20.0;        ///< [Hz] most ~estimate messages per second
  bool publish_markers = true;
  BondColouring color_bonds_by = BondColouring::kStrain;
  double particle_diameter_m = 0.02;
  double tf_timeout_sec = 0.05;
  bool vicon_qualify_with_subject = false;  ///< names "subject/marker" for vicon input
  std::string model_dir;               ///< services only touch files under it ("" = ROS home)
  std::string autosave_path;           ///< "" = off; relative paths are inside model_dir
  double autosave_period_sec = 10.0;   ///< [s] between autosaves
  std::string initial_model;           ///< resume from this model file when it exists
  double prediction_period_sec = PredictionMonitor::kDefaultPeriodS;  ///< [s]; 0 = off
  /// Choose the structure from the markers on the first full window and on ~reset; the model
  /// may then hold the particles alone (structure_selection.h).
  bool select_structure = false;
  std::string structure_report_path = "structure_report.csv";  ///< inside model_dir
  /// [s] wall time of one structure selection (0 = no limit): a cut selection chooses the best
  /// level judged so far (StructureOptions::max_wall_time_s).
  double structure_max_time_s = 120.0;
  /// Add sensor muscles to the estimated passive model in the background and keep their linear
  /// part refitted on the window (muscle_job.h). Default: on with select_structure, else off.
  bool sensor_muscles = false;
  /// The muscle job: its fit's sensors (~muscle_sensors) and time limit
  /// (~muscles_max_time_sec), the refit period (~muscle_refit_period_sec); min_frames follows
  /// ~window_frames.
  MuscleJobOptions muscles = defaultMuscleJobOptions();
  /// Niceness (0..19) of the node's background threads (refinements, structure selection, sensor
  /// muscles, ~markers drawing), so that on busy cores the worker gets them first (0: as the
  /// worker's).
  int background_nice = 10;
  IslandLinkOptions islands;
  OnlineEstimatorOptions estimator;
};

/// "markers" | "pointcloud" | "vicon" -> the enum; false when unknown.
bool parseInputType(const std::string& text, InputType* type);
const char* inputTypeName(InputType type);

/// Named values, as the parameter server holds them (names without the "~").
class ParameterSource {
 public:
  virtual ~ParameterSource() = default;
  /// False when `name` is not set (the value is left as it is). Throws InputError naming
  /// "~name" when it is set with a type that does not convert.
  virtual bool get(const std::string& name, std::string* value) const = 0;
  virtual bool get(const std::string& name, double* value) const = 0;
  virtual bool get(const std::string& name, int* value) const = 0;
  virtual bool get(const std::string& name, bool* value) const = 0;
};

/// Every option from `params`, defaults where unset, checked. `~model_dir` unset: $ROS_HOME, else
/// $HOME/.ros. Throws InputError naming the first bad parameter and what it must be.
EstimatorNodeOptions readEstimatorNodeOptions(const ParameterSource& params);

}  // namespace mme

#include "motion_model_estimation/ros/simulator_publisher.h"

#include <cmath>

#include "motion_model_estimation/MarkerFrame.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/ros/conversions.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace mme {

std::string validateOptions(const SimulatorPublisherOptions& o) {
  if (o.model_path.empty() == o.scene.empty()) return "~model / ~scene: give exactly one";
  if (!(o.rate_scale > 0.0) || !std::isfinite(o.rate_scale)) return "~rate_scale must be > 0";
  if (!(o.noise_std_m >= 0.0) || !std::isfinite(o.noise_std_m))
    return "~noise_std_m must be >= 0";
  if (o.max_frames < 0) return "~max_frames must be >= 0";
  if (!(o.frame_rate_hz >= 0.0) || !std::isfinite(o.frame_rate_hz))
    return "~frame_rate_hz must be >= 0";
  if (!o.step_param.empty()) {
    if (!(o.step_factor > 0.0) || !std::isfinite(o.step_factor))
      return "~step_factor must be > 0";
    if (o.step_after_frames < 1) return "~step_after_frames must be >= 1 when ~step_param is set";
  }
  return "";
}

namespace {
Model loadModel(const SimulatorPublisherOptions& o) {
  Model model = o.scene.empty() ? loadModelFile(o.model_path) : makeScene(o.scene).model;
  if (o.frame_rate_hz > 0.0) model.frame_rate_hz = o.frame_rate_hz;
  if (!(model.frame_rate_hz > 0.0))
    throw InputError("the model has no frame_rate_hz: set ~frame_rate_hz");
  if (!o.frame_id.empty()) model.frame_id = o.frame_id;
  return model;
}
}  // namespace

SimulatorPublisher::SimulatorPublisher(ros::NodeHandle& nh, const SimulatorPublisherOptions& options)
    : options_(options),
      model_(loadModel(options)),
      simulator_(model_),
      state_(simulator_.initialState()),
      rng_(static_cast<uint64_t>(options.seed)) {
  step_ref_.bond_type = -2;
  if (!options_.step_param.empty()) {
    bool found = false;
    for (const ParamRef& ref : presentParameters(model_))
      if (ref.name == options_.step_param) {
        step_ref_ = ref;
        found = true;
      }
    if (!found)
      throw InputError("~step_param '" + options_.step_param +
                       "' is not a parameter of the model (expected <bond_type>/<param>)");
  }
  publisher_ = nh.advertise<motion_model_estimation::MarkerFrame>("markers", 100);
}

void SimulatorPublisher::publishFrame() {
  Trajectory frame;
  frame.frame_rate_hz = model_.frame_rate_hz;
  for (const Particle& p : model_.particles) frame.marker_names.push_back(p.name);
  frame.resize(1);
  frame.frame_numbers[0] = frame_number_;
  for (int i = 0; i < frame.numMarkers(); ++i) {
    frame.position(0, i) = state_.x_m[i];
    frame.occluded[i] = 0;
  }
  // A different seed per frame keeps the noise reproducible for a given seed and frame number.
  addGaussianNoise(&frame, options_.noise_std_m, rng_());
  publisher_.publish(toMarkerFrameMsg(frame, 0, model_.frame_id, ros::Time::now()));
  ++frame_number_;
}

void SimulatorPublisher::applyStep() {
  const double before = getParam(model_, step_ref_);
  setParam(model_, step_ref_, before * options_.step_factor);
  simulator_.setParameters(model_);
  ROS_INFO("simulator_node: after frame %u, %s steps from %g to %g", frame_number_ - 1,
           step_ref_.name.c_str(), before, getParam(model_, step_ref_));
}

void SimulatorPublisher::spin() {
  const double frame_period_s = 1.0 / model_.frame_rate_hz;
  ros::Rate rate(model_.frame_rate_hz * options_.rate_scale);
  ROS_INFO("simulator_node: publishing %zu markers at %.3g Hz on %s", model_.particles.size(),
           model_.frame_rate_hz * options_.rate_scale, publisher_.getTopic().c_str());
  while (ros::ok()) {
    publishFrame();
    if (options_.max_frames > 0 && frame_number_ >= static_cast<uint32_t>(options_.max_frames)) {
      ROS_INFO("simulator_node: published %u frames, done", frame_number_);
      break;
    }
    // Frames 0 .. step_after_frames-1 come from the old value, the motion after them from the
    // new one.
    if (step_ref_.bond_type != -2 &&
        frame_number_ == static_cast<uint32_t>(options_.step_after_frames))
      applyStep();
    simulator_.stepFrame(&state_, frame_period_s);
    bool finite = true;
    for (const Eigen::Vector3d& x : state_.x_m) finite = finite && x.allFinite();
    if (!finite) {
      ROS_ERROR("simulator_node: the simulation diverged at frame %u; stopping", frame_number_);
      break;
    }
    ros::spinOnce();
    rate.sleep();
  }
}

}  // namespace mme

// Rosbags of MarkerFrame as a trajectory format of the tools (io/trajectory_io.h): the ROS
// layer adds it, so that the core reads and writes TRC and C3D without ROS and a ROS build
// reads and writes bags through the same entry point.
#pragma once

namespace mme {

/// Registers ".bag" (readBag / writeBag, bag_io.h) with registerTrajectoryFormat. Idempotent.
void registerBagFormat();

}  // namespace mme

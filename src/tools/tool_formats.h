// The trajectory formats a tool reads and writes beyond the core's TRC and C3D: the ROS build
// adds rosbags (tool_formats_ros.cpp), the ROS-free build nothing (tool_formats_core.cpp). One
// of the two is linked into every tool, so the tools' code is the same in both builds.
#pragma once

namespace mme {

/// Registers the build's extra formats with io/trajectory_io.h. Call once, first thing in main.
void registerToolFormats();

}  // namespace mme

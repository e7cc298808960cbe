// Reading private params without silent fallbacks: a param that is set with the wrong type is an
// error naming it, a param that is not set keeps the documented default.
#pragma once

#include <ros/ros.h>

#include <string>

namespace mme {

/// Reads `~name` into *value when set. Returns false and fills *error when it is set with a type
/// that does not convert.
template <typename T>
bool readParam(const ros::NodeHandle& pnh, const std::string& name, T* value, std::string* error) {
  if (!pnh.hasParam(name)) return true;
  if (pnh.getParam(name, *value)) return true;
  *error = "~" + name + " has the wrong type";
  return false;
}

}  // namespace mme

#include "tool_formats.h"

#include "motion_model_estimation/ros/bag_format.h"

namespace mme {

void registerToolFormats() { registerBagFormat(); }

}  // namespace mme

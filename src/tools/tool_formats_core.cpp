#include "tool_formats.h"

namespace mme {

void registerToolFormats() {}  // the ROS-free build: TRC and C3D only

}  // namespace mme

// The one exception type for bad input (files, parameters): its message is shown to the user.
#pragma once

#include <stdexcept>
#include <string>

namespace mme {

/// Bad user input. what() names the file (and line and key where known) and the reason, e.g.
/// "model.yaml:12: key 'stifness': unknown key in bond type 's01'".
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace mme

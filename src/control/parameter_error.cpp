#include "selfsense/control/parameter_error.hpp"

namespace selfsense::control {

void require_valid(bool valid, const std::string& why) {
  if (!valid) throw ParameterError(why);
}

}  // namespace selfsense::control

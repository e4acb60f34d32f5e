#include "bem/version.hpp"
namespace bem {
const char* version() { return "0.1.0"; }
}  // namespace bem

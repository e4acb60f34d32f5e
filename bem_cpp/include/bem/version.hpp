#pragma once
namespace bem {
/// Library version string.
const char* version();
}  // namespace bem

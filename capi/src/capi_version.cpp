// The C ABI's versions: the library's (CSC_VERSION_* of csculpt.h, checked against the project's
// version in CMake, CSCULPT_VERSION_*) and the wire protocol's.
#include "capi_internal.h"
#include "csculpt/wire.h"

static_assert(
    CSC_VERSION_MAJOR == CSCULPT_VERSION_MAJOR && CSC_VERSION_MINOR == CSCULPT_VERSION_MINOR &&
        CSC_VERSION_PATCH == CSCULPT_VERSION_PATCH,
    "csculpt.h's CSC_VERSION_* must equal project(csculpt VERSION ...) in CMakeLists.txt");

extern "C" {

CSC_API uint32_t csc_version(void) {
  return CSC_VERSION_NUMBER;
}
CSC_API const char* csc_version_string(void) {
  return CSC_VERSION_STRING;
}
CSC_API uint32_t csc_wire_protocol_version(void) {
  return csculpt::wire_protocol_version;
}

}  // extern "C"

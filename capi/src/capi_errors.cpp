// The C ABI's errors: the thread-local message behind csc_last_error() and the status names.
#include <string>

#include "capi_internal.h"

namespace csculpt::capi {
namespace {

thread_local std::string t_last_error;

}  // namespace

csc_status fail(csc_status status, std::string message) {
  try {
    t_last_error = std::move(message);
  } catch (...) {
    t_last_error.clear();
  }
  return status;
}

[[noreturn]] void bad_argument(std::string message) {
  throw ArgumentError{std::move(message)};
}

}  // namespace csculpt::capi

using namespace csculpt::capi;

extern "C" {

CSC_API const char* csc_status_str(csc_status status) {
  switch (status) {
    case CSC_OK:
      return "ok";
    case CSC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case CSC_ERROR_INVALID_INPUT:
      return "invalid input";
    case CSC_ERROR_IO:
      return "input/output error";
    case CSC_ERROR_UNKNOWN_BASE_VERSION:
      return "unknown base version";
    case CSC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case CSC_ERROR_INTERNAL:
      return "internal error";
    default:
      return "unknown status";
  }
}

CSC_API const char* csc_last_error(void) {
  return t_last_error.c_str();
}

}  // extern "C"

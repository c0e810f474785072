// The app's one wording of a failed C ABI call, for the panel and stderr.
#pragma once

#include <csculpt.h>

#include <string>

/** "WHAT: STATUS: DETAIL", DETAIL being csc_last_error() of this thread's last failed call. */
inline std::string abi_error(const char* what, csc_status status) {
  return std::string(what) + ": " + csc_status_str(status) + ": " + csc_last_error();
}

// csculpt.h alone, first, as C++11 with strict warnings: self-contained and extern "C".
#include "csculpt.h"

// Every _INIT macro as a C++ initialiser, and the 32-bit enums: the C99 checks, as C++.
#include "header_c.c"

// The functions must have C linkage (taking their address as a pointer to an extern "C"
// function type).
extern "C" typedef csc_status csc_peek_fn(const void*, size_t, csc_message_info*);
int csculpt_header_cpp_check();
int csculpt_header_cpp_check() {
  csc_peek_fn* peek = &csc_diff_peek;
  return csculpt_header_c_check() + (peek != nullptr ? 1 : 0);
}

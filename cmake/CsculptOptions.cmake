# Project-wide compiler settings: warnings, determinism, sanitizers.
#
# CSCULPT_SANITIZE: "" (off), "address" (ASan+UBSan), or "thread" (TSan).
set(CSCULPT_SANITIZE "" CACHE STRING "Sanitizers: '', 'address' (ASan+UBSan) or 'thread' (TSan)")
set_property(CACHE CSCULPT_SANITIZE PROPERTY STRINGS "" address thread)

add_library(csculpt_warnings INTERFACE)
add_library(csculpt::warnings ALIAS csculpt_warnings)
target_compile_options(csculpt_warnings INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
  -Wconversion -Wno-sign-conversion -Wcast-align -Woverloaded-virtual>
  $<$<COMPILE_LANGUAGE:C>:-Wall -Wextra -Wpedantic>)
# Off by default, so a user's plain build is not stopped by a compiler's false positive (GCC 12's
# -Wrestrict in libstdc++); ./dev (and so CI) turns it on to hold the warnings at zero.
option(CSCULPT_WERROR "Treat warnings as errors" OFF)
if(CSCULPT_WERROR)
  target_compile_options(csculpt_warnings INTERFACE -Werror)
endif()

# Determinism: every peer must compute bit-identical merges. No fused multiply-add
# contraction (its availability differs by CPU), no fast-math, no -march=native.
add_compile_options(-ffp-contract=off -fno-fast-math)

# GCC's -Wmaybe-uninitialized gives false positives inside libstdc++ once sanitizer
# instrumentation is on (GCC bug 105562 and kin); the release build keeps the warning.
if(CSCULPT_SANITIZE STREQUAL "address")
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
                      -Wno-maybe-uninitialized)
  add_link_options(-fsanitize=address,undefined)
elseif(CSCULPT_SANITIZE STREQUAL "thread")
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer -Wno-maybe-uninitialized)
  add_link_options(-fsanitize=thread)
elseif(NOT CSCULPT_SANITIZE STREQUAL "")
  message(FATAL_ERROR "CSCULPT_SANITIZE must be '', 'address' or 'thread'")
endif()

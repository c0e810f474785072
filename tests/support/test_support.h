// Shared GoogleTest helpers.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "csculpt/error.h"

namespace csculpt::test {

/// Runs fn, which must throw csculpt::InvalidInput, and returns the message (else a failure).
template <class Fn>
std::string invalid_input_message(Fn&& fn) {
  try {
    fn();
  } catch (const csculpt::InvalidInput& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected InvalidInput";
  return {};
}

}  // namespace csculpt::test

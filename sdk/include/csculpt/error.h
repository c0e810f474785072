// Typed exceptions inside the SDK; the C ABI maps them to status codes.
#pragma once

#include <stdexcept>
#include <string>

namespace csculpt {

/// Input that cannot be used: malformed file, mismatched connectivity, NaN/Inf, bad index.
/// The message says what is wrong and where (file name, element index) so a caller can
/// show it to a person unchanged.
class InvalidInput : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file could not be opened, read or written.
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace csculpt

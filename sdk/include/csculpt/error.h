// Typed exceptions inside the SDK; the C ABI maps them to status codes.
#pragma once

#include <new>
#include <stdexcept>
#include <string>
#include <utility>

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

/// Memory ran out; the message says what was being done (e.g. the file being read). A
/// std::bad_alloc, so whoever handles running out of memory still catches it.
class OutOfMemory : public std::bad_alloc {
 public:
  explicit OutOfMemory(std::string message) : message_(std::move(message)) {}
  const char* what() const noexcept override { return message_.c_str(); }

 private:
  std::string message_;
};

}  // namespace csculpt

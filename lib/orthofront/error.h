#pragma once
/// Typed exceptions thrown at the library boundary (never inside per-vertex loops).
#include <stdexcept>
#include <string>

namespace orthofront {

/// Base of every error the project throws on purpose.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A parameter, specification or input value is not acceptable; the message names it.
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

}  // namespace orthofront

#pragma once
/// I/O errors: every message names the file (and dataset/value where there is one).
#include "orthofront/error.h"

namespace orthofront::io {

/// A file cannot be opened, read, written or renamed.
class IoError : public Error {
 public:
  using Error::Error;
};

/// A file was read but its content is not what the format requires.
class FormatError : public Error {
 public:
  using Error::Error;
};

}  // namespace orthofront::io

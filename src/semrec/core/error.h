// Typed errors. Every message names the offending file (when there is one) and
// says what is wrong, so that a user can fix the input without reading the
// source.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace semrec {

/// Base of all semrec errors.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An error about one file; the message starts with its path.
class FileError : public Error {
 public:
  FileError(const std::filesystem::path& path, const std::string& problem)
      : Error(path.string() + ": " + problem), path_(path) {}
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// A file or folder is missing or cannot be read / written.
class IoError : public FileError {
 public:
  using FileError::FileError;
};

/// A file exists but its content is wrong (corrupt image, malformed pose, bad
/// manifest, ...).
class FormatError : public FileError {
 public:
  using FileError::FileError;
};

/// An option or argument has an invalid value.
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

/// Throws InvalidArgument(message) unless `condition` holds. For
/// Options::Check().
inline void CheckArgument(bool condition, const std::string& message) {
  if (!condition) throw InvalidArgument(message);
}

}  // namespace semrec

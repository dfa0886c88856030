// Exception types: every error names the file, field or value that was wrong.
#pragma once

#include <stdexcept>
#include <string>

namespace dynscope {

/// Base of every dynscope exception; `what()` is one human-readable line.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// A file could not be opened, read or written; the message starts with the path.
class IoError : public Error {
 public:
  IoError(const std::string& path, const std::string& message)
      : Error(path + ": " + message), path_(path) {}
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// A file was readable but a field in it is missing or malformed ("path: field: message").
class FormatError : public IoError {
 public:
  FormatError(const std::string& path, const std::string& field, const std::string& message)
      : IoError(path, field + ": " + message), field_(field) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

/// An argument or value is out of its valid range ("name: message").
class ValueError : public Error {
 public:
  ValueError(const std::string& name, const std::string& message)
      : Error(name + ": " + message), name_(name) {}
  const std::string& name() const { return name_; }

 private:
  std::string name_;
};

}  // namespace dynscope

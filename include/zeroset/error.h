#pragma once
/// The exceptions the core throws. Front ends catch `Error`: `BadInput` and its subclasses
/// (IoError included) are the user's to fix (CLI exit code 2), everything else (WriteError
/// included) is a runtime failure (exit 1).
#include <stdexcept>
#include <string>

namespace zeroset {

/// Base of every zeroset exception.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The input (an equation, a flag, a file's content, a parameter value) is wrong.
class BadInput : public Error {
 public:
  using Error::Error;
};

/// A parse error: `what()` is the full formatted message (with line, column and caret line).
class ParseError : public BadInput {
 public:
  ParseError(std::string message, int line, int column, std::string formatted)
      : BadInput(std::move(formatted)),
        message_(std::move(message)),
        line_(line),
        column_(column) {}
  const std::string& message() const { return message_; }
  int line() const { return line_; }      ///< 1-based
  int column() const { return column_; }  ///< 1-based, in characters of that line

 private:
  std::string message_;
  int line_;
  int column_;
};

/// An option or parameter has a value that cannot be used; the message names both.
class InvalidArgument : public BadInput {
 public:
  InvalidArgument(const std::string& name, const std::string& value, const std::string& why)
      : BadInput(name + " = " + value + ": " + why) {}
  explicit InvalidArgument(const std::string& message) : BadInput(message) {}
};

/// A setting (a key of a scene file's "floaters", "mesh" or "render" object) has a value its
/// rule refuses. The settings' validators throw it; each entry point names the setting its own
/// way (a flag, a JSON pointer, a viewer command's key) and passes why() on unchanged, so one
/// bad value gets the same words everywhere.
class SettingError : public InvalidArgument {
 public:
  SettingError(const std::string& key, const std::string& value, const std::string& why)
      : InvalidArgument(key, value, why), key_(key), value_(value), why_(why) {}
  const std::string& key() const { return key_; }      ///< e.g. "max_count", "front/diffuse"
  const std::string& value() const { return value_; }  ///< the refused value as text
  const std::string& why() const { return why_; }      ///< e.g. "must lie in [1, 100000000]"

 private:
  std::string key_;
  std::string value_;
  std::string why_;
};

/// A file the user named cannot be used as given: an input file that cannot be read (or is
/// malformed), or an output path that is wrong before any work starts (its directory is
/// missing or not writable, it is a directory). The user's to fix: exit code 2. The message is
/// "'path': reason".
class IoError : public BadInput {
 public:
  IoError(const std::string& path, const std::string& reason)
      : BadInput("'" + path + "': " + reason), path_(path) {}
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// Writing an output failed during or after the work (disk full, an I/O error, a rename that
/// failed): a runtime failure, not the user's input (exit code 1). The message is
/// "'path': reason".
class WriteError : public Error {
 public:
  WriteError(const std::string& path, const std::string& reason)
      : Error("'" + path + "': " + reason), path_(path) {}
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// An internal invariant does not hold: a bug in zeroset.
#define ZS_ASSERT(cond)                                                                          \
  do {                                                                                           \
    if (!(cond))                                                                                 \
      throw ::zeroset::Error(std::string("internal error: ") + #cond + " at " + __FILE__ + ":" + \
                             std::to_string(__LINE__));                                          \
  } while (0)

}  // namespace zeroset

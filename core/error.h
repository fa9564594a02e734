// Error types. Input and command-line layers throw; kernels never do (they return status or check).
#pragma once

#include <stdexcept>
#include <string>

namespace aarad {

// Any error aarad reports to a user.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A problem in an input file. what() reads "file:line: message" (or "file: message" without a line),
// the form compilers use, so editors can jump to it.
class InputError : public Error {
 public:
  InputError(std::string file, int line, const std::string& message)
      : Error(format(file, line, message)), file_(std::move(file)), line_(line), message_(message) {}

  const std::string& file() const { return file_; }
  int line() const { return line_; }  // 0 when the problem has no line
  const std::string& message() const { return message_; }

  static std::string format(const std::string& file, int line, const std::string& message) {
    return line > 0 ? file + ":" + std::to_string(line) + ": " + message : file + ": " + message;
  }

 private:
  std::string file_;
  int line_;
  std::string message_;
};

}  // namespace aarad

// Error types. Input and command-line layers throw; kernels never do (they return status or check).
#pragma once

#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>

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

// `text` as a message may show it on a terminal: a control character (a NUL, an escape sequence, a line end) of a
// name or a word read from a file is written as \xNN, so it neither cuts the message short (a NUL ended what())
// nor acts on the terminal. Other bytes, UTF-8 among them, are kept.
inline std::string printable(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte != 0x7F) {
      out += c;
    } else {
      char escaped[5];
      std::snprintf(escaped, sizeof escaped, "\\x%02X", byte);
      out += escaped;
    }
  }
  return out;
}

}  // namespace aarad

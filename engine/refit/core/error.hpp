#pragma once
// One error type for bad input: its message is the single line a user sees,
// naming the file (and line) and the problem.
#include <cstddef>
#include <stdexcept>
#include <string>

namespace refit {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// Input this machine cannot afford (an estimate above the memory there is):
/// the command line exits 3, not 1.
class ResourceError : public Error {
 public:
  using Error::Error;
};

/// "file: problem" or "file:line: problem".
inline Error input_error(const std::string& file, const std::string& problem, std::size_t line = 0) {
  std::string where = file.empty() ? std::string("<input>") : file;
  if (line > 0) (where += ':') += std::to_string(line);  // not ":" + string: GCC 12's false -Wrestrict (bug 105329)
  return Error(where + ": " + problem);
}

}  // namespace refit

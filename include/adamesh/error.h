// Error reporting: adamesh functions throw adamesh::Error carrying a Status and a one-line message
// that names the file (or input) and the problem, e.g. "head.nrrd: truncated data: expected ...".
#pragma once

#include <stdexcept>
#include <string>

namespace adamesh {

/// Outcome classes. The CLI uses the numeric values as exit codes.
enum class Status : int {
  ok = 0,
  usage = 1,           ///< bad command line
  invalid_input = 2,   ///< missing, truncated, corrupt or inconsistent input
  unsupported = 3,     ///< valid input using a feature adamesh does not implement
  output_failed = 4,   ///< an output file could not be written
  internal = 5,        ///< a broken invariant inside adamesh (a bug)
  cancelled = 6,       ///< the caller's cancellation flag was set (ExecutionContext::cancel)
};

const char* to_string(Status s) noexcept;

class Error : public std::runtime_error {
 public:
  Error(Status status, const std::string& message) : std::runtime_error(message), status_(status) {}
  Status status() const noexcept { return status_; }

 private:
  Status status_;
};

/// Throws Error(status, message).
[[noreturn]] void fail(Status status, const std::string& message);

/// Throws Error(Status::invalid_input, "<where>: <what>").
[[noreturn]] void fail_input(const std::string& where, const std::string& what);

}  // namespace adamesh

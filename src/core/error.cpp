#include "adamesh/error.h"

namespace adamesh {

const char* to_string(Status s) noexcept {
  switch (s) {
    case Status::ok: return "ok";
    case Status::usage: return "usage";
    case Status::invalid_input: return "invalid input";
    case Status::unsupported: return "unsupported";
    case Status::output_failed: return "output failed";
    case Status::internal: return "internal error";
    case Status::cancelled: return "cancelled";
  }
  return "unknown";
}

void fail(Status status, const std::string& message) { throw Error(status, message); }

void fail_input(const std::string& where, const std::string& what) {
  throw Error(Status::invalid_input, where.empty() ? what : where + ": " + what);
}

}  // namespace adamesh

// status_of(): the Status of the Error a call throws (tests that link the library).
#pragma once

#include <functional>

#include "adamesh/error.h"

namespace adamesh::testutil {

/// The Status of the Error f() throws, Status::ok when it returns.
inline Status status_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.status();
  }
  return Status::ok;
}

}  // namespace adamesh::testutil

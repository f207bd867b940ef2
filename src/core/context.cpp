#include "adamesh/context.h"

#include "adamesh/error.h"

namespace adamesh {

const ExecutionContext& default_context() noexcept {
  static const ExecutionContext context;
  return context;
}

void ExecutionContext::check_cancelled() const {
  if (cancelled()) fail(Status::cancelled, "cancelled");
}

void ExecutionContext::report(const char* stage, double fraction) const {
  check_cancelled();
  if (progress) progress(stage, fraction);
}

}  // namespace adamesh

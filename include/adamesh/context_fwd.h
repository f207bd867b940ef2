// The execution context by name only, for headers that take one (surfels.h, simplify.h,
// refine.h, improve.h, metrics.h): they stay free of <functional> and <atomic>. Callers that set
// threads, progress or cancellation include adamesh/context.h.
#pragma once

namespace adamesh {

struct ExecutionContext;

/// A default-constructed ExecutionContext (all hardware threads, no progress, no cancellation):
/// the default argument of every stage function. Immutable; safe to share between threads.
const ExecutionContext& default_context() noexcept;

}  // namespace adamesh

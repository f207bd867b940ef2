// Atomic output: write to a temporary file next to the target, then rename over it.
// A failure (exception, full disk, unwritable directory) never leaves a partial file behind.
#pragma once

#include <functional>
#include <iosfwd>
#include <string>

namespace adamesh {

/// Calls write(stream) on a temporary file in the target's directory, flushes, checks the stream
/// and renames it to `path`. Throws Error(Status::output_failed, "<path>: ...") on any failure
/// and removes the temporary file; exceptions thrown by `write` propagate after the clean-up.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary = true);

}  // namespace adamesh

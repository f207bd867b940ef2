// Atomic, safe output files: write to a temporary file created exclusively next to the target,
// then rename over it. A failure (exception, full disk, unwritable folder) never leaves a partial
// file behind, an existing symlink/device/directory at the target is refused, and temporaries of
// processes that died (kill -9) are cleaned up by the next write of the same target.
#pragma once

#include <functional>
#include <iosfwd>
#include <string>

namespace adamesh {

/// Throws Error(Status::output_failed, "<path>: ...") unless `path` can take an output file:
/// it is absent or a regular file (not a symlink, directory, device, FIFO or socket), and its
/// folder exists and is writable. write_file_atomically() calls it first; callers may call it
/// earlier to refuse a bad path before any work.
void check_output_target(const std::string& path);

/// Name prefix of the temporary files for a target file named `target_name` (no folder):
/// ".<target_name>.adamesh-tmp-" followed by "<pid>-<n>".
std::string temporary_file_prefix(const std::string& target_name);

/// Calls write(stream) on a temporary file in the target's folder (created with
/// O_CREAT|O_EXCL|O_NOFOLLOW), flushes, checks the stream and renames it to `path`. Throws
/// Error(Status::output_failed, "<path>: ...") on any failure and removes the temporary file;
/// exceptions thrown by `write` propagate after the clean-up. `binary` is kept for source
/// compatibility (POSIX files do not distinguish text and binary).
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary = true);

}  // namespace adamesh

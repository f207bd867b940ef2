// Helpers shared by the file readers and writers in src/io.
#pragma once

#include <string>

namespace adamesh::detail {

/// Lower-case extension including the dot, with ".gz" kept as part of it: "a.nii.gz" -> ".nii.gz".
std::string lower_extension(const std::string& path);

}  // namespace adamesh::detail

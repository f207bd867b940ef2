// Internal entry points of the volume readers (one .cpp per format in src/io); read_volume()
// in read_volume.cpp picks one by extension and magic. Each returns a volume with grid, type,
// format and source set, or throws Error(invalid_input | unsupported, "<path>: <problem>").
#pragma once

#include <string>

#include "adamesh/input.h"
#include "adamesh/volume.h"

namespace adamesh::detail {

Volume read_nrrd(const std::string& path);
Volume read_metaimage(const std::string& path);
Volume read_nifti(const std::string& path);
Volume read_vtk_legacy(const std::string& path);
Volume read_vti(const std::string& path);
Volume read_slc(const std::string& path);
Volume read_mrc(const std::string& path);
Volume read_raw(const std::string& path, const RawOptions& raw);

}  // namespace adamesh::detail

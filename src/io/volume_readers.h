// Internal entry points of the volume readers (one .cpp per format in src/io); read_volume()
// in read_volume.cpp picks one by extension and magic. Each returns a volume with grid, type,
// format and source set, or throws Error(invalid_input | unsupported, "<path>: <problem>").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

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
/// DICOM series (dicom.cpp, GDCM): `path` is a directory, or one slice whose directory holds the
/// series. `series_uid` empty: the only series there (several: Error(usage) listing them).
Volume read_dicom(const std::string& path, const std::string& series_uid);
/// The series `series_uid` (empty: the only one) among `files`; `where` names them in messages.
Volume read_dicom_series(const std::vector<std::string>& files, const std::string& where,
                         const std::string& series_uid);
/// True when the file has the DICOM Part 10 preamble ("DICM" at byte 128).
bool is_dicom_file(const std::string& path);
/// DICOM reads whose child process died without a result, since the start (fuzz_dicom's triage
/// counts them: an error message can contain any text the files hold).
std::uint64_t dicom_child_failures() noexcept;

}  // namespace adamesh::detail

// File input and output: volumes (NRRD, MetaImage, NIfTI-1/2, VTK legacy and XML ImageData,
// DICOM series, VolVis SLC, CCP4/MRC, headerless raw) and triangle meshes (PLY, OBJ, OFF, STL; glTF/GLB
// written only).
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "adamesh/input.h"
#include "adamesh/mesh.h"
#include "adamesh/volume.h"

namespace adamesh {

/// Reads a volume file; the format is chosen by extension and checked against the file's magic.
/// A directory is read as a DICOM series (raw.dicom_series picks one when there are several).
/// Raw files (`.raw` or any file when raw.dims is set) need raw.dims and raw.type.
/// Throws Error(invalid_input | unsupported, "<path>: <problem>").
Volume read_volume(const std::string& path, const RawOptions& raw = {});

/// DICOM series from a list of files (any order; files that are not DICOM images are ignored):
/// the series `series_uid`, or the only one. A directory (or one slice of the series) can also be
/// given to read_volume(). Geometry and refusals: docs/FORMATS.md, "DICOM". Throws Error
/// (invalid_input | unsupported | usage when several series need a choice).
Volume read_dicom_series(const std::vector<std::string>& files, const std::string& series_uid = "");

/// Name of the format read_volume() would use for `path` ("NRRD", "MetaImage", ...).
/// Never throws: "" when neither the extension nor the file's magic is recognised (a file that
/// cannot be opened is judged by its extension alone). See docs/FORMATS.md.
std::string volume_format_for(const std::string& path, const RawOptions& raw = {});

enum class MeshFormat { automatic, ply, obj, off, stl, glb, gltf };

struct MeshWriteOptions {
  MeshFormat format = MeshFormat::automatic;  ///< automatic: from the extension
  bool ascii = false;                         ///< PLY: ASCII instead of binary little-endian
  bool write_normals = true;                  ///< when the mesh has normals
  bool write_attributes = true;               ///< PLY: per-vertex attributes as properties
  /// glTF/GLB only: EXT_meshopt_compression (lossless meshopt codecs; the file then needs a
  /// reader that knows the extension, e.g. three.js with MeshoptDecoder, Blender, gltfpack).
  bool compress = false;
};

/// The format write_mesh() picks for `path` from its extension; automatic when none fits.
MeshFormat mesh_format_from_path(const std::string& path);

/// The format write_mesh() would use for `path` with `options` (from the extension when
/// options.format is automatic). Call it before any computing to refuse a bad output name early.
/// Throws Error(unsupported, "<path>: unknown mesh format (use ...)") for an unknown extension,
/// or when options.compress is set for a format other than glTF/GLB.
MeshFormat mesh_format_for_writing(const std::string& path, const MeshWriteOptions& options = {});

/// Writes atomically (temporary file + rename); `.gltf` also writes its buffer to the same name
/// with the extension `.bin`. Throws Error(output_failed, "<path>: ..."), or Error(unsupported)
/// as mesh_format_for_writing() does.
void write_mesh(const Mesh& mesh, const std::string& path, const MeshWriteOptions& options = {});

/// Writes the mesh to a stream (standard output, a pipe, memory) in options.format, which must be
/// named: ply, obj, off, stl or glb — the byte-identical content write_mesh() gives a file of that
/// format. `name` is used in messages. Throws Error(usage) for MeshFormat::automatic,
/// Error(unsupported) for gltf (two files) or compress with a format other than glb, and
/// Error(output_failed, "<name>: ...") for an inconsistent mesh (nothing written) or a failing
/// stream.
void write_mesh_to_stream(const Mesh& mesh, std::ostream& os, const MeshWriteOptions& options,
                          const std::string& name = "-");

/// Reads PLY (ASCII/binary), OBJ, OFF or STL (binary/ASCII; corners with identical positions
/// merged). Format from the extension, else from the first bytes. Polygons are fan-triangulated.
/// Throws Error(invalid_input, "<path>: <problem>") on missing, truncated or inconsistent files.
Mesh read_mesh(const std::string& path);

}  // namespace adamesh

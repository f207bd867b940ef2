// read_volume(): a directory (or a DICOM file) is a DICOM series (dicom.cpp); otherwise picks
// the volume reader from the file extension and checks it against the
// file's magic bytes (a file whose content is clearly another supported format is rejected
// with a message naming both); unknown extensions are identified by their magic alone.
#include <cstring>
#include <filesystem>
#include <string_view>

#include "adamesh/error.h"
#include "adamesh/io.h"
#include "io_util.h"
#include "volume_readers.h"

namespace adamesh {
namespace {

using detail::InputFile;

enum class Fmt { unknown, nrrd, metaimage, nifti, vtk, vti, slc, mrc, raw };

const char* format_name(Fmt f) {
  switch (f) {
    case Fmt::nrrd: return "NRRD";
    case Fmt::metaimage: return "MetaImage";
    case Fmt::nifti: return "NIfTI-1";
    case Fmt::vtk: return "VTK legacy";
    case Fmt::vti: return "VTK XML ImageData";
    case Fmt::slc: return "VolVis SLC";
    case Fmt::mrc: return "MRC";
    case Fmt::raw: return "raw";
    case Fmt::unknown: break;
  }
  return "";
}

Fmt from_extension(const std::string& ext) {
  if (ext == ".nrrd" || ext == ".nhdr") return Fmt::nrrd;
  if (ext == ".mhd" || ext == ".mha") return Fmt::metaimage;
  if (ext == ".nii" || ext == ".nii.gz" || ext == ".hdr" || ext == ".hdr.gz" || ext == ".img" ||
      ext == ".img.gz")
    return Fmt::nifti;
  if (ext == ".vtk") return Fmt::vtk;
  if (ext == ".vti") return Fmt::vti;
  if (ext == ".slc") return Fmt::slc;
  if (ext == ".mrc" || ext == ".map" || ext == ".ccp4" || ext == ".mrcs") return Fmt::mrc;
  if (ext == ".raw") return Fmt::raw;
  return Fmt::unknown;
}

std::int32_t int32_at(const std::string& s, std::size_t off, bool swap) {
  std::uint32_t v = 0;
  std::memcpy(&v, s.data() + off, 4);
  if (swap) v = __builtin_bswap32(v);
  return static_cast<std::int32_t>(v);
}

bool starts_with(std::string_view s, std::string_view p) { return s.substr(0, p.size()) == p; }

// Identifies a format from the first bytes of a file (uncompressed files only).
Fmt sniff(const std::string& head, bool* nifti2 = nullptr) {
  if (starts_with(head, "NRRD000")) return Fmt::nrrd;
  if (starts_with(head, "# vtk DataFile")) return Fmt::vtk;
  if (head.find("<VTKFile") != std::string::npos && head.find("ImageData") != std::string::npos)
    return Fmt::vti;
  if (starts_with(head, "11111") && head.size() > 5 &&
      std::strchr(" \t\r\n", head[5]) != nullptr)
    return Fmt::slc;
  if (head.size() >= 348) {
    for (bool swap : {false, true}) {
      if (int32_at(head, 0, swap) == 348 &&
          (head.compare(344, 4, std::string("n+1\0", 4)) == 0 ||
           head.compare(344, 4, std::string("ni1\0", 4)) == 0))
        return Fmt::nifti;
      if (int32_at(head, 0, swap) == 540 &&
          (head.compare(4, 4, std::string("n+2\0", 4)) == 0 ||
           head.compare(4, 4, std::string("ni2\0", 4)) == 0)) {
        if (nifti2) *nifti2 = true;
        return Fmt::nifti;
      }
    }
  }
  if (head.size() >= 1024 && head.compare(208, 4, "MAP ") == 0) return Fmt::mrc;
  // MetaImage: the first non-blank line is "Key = value" with a MetaIO key.
  std::size_t i = 0;
  while (i < head.size() && std::strchr(" \t\r\n", head[i]) != nullptr) ++i;
  for (const char* key : {"ObjectType", "NDims", "ObjectSubType", "Comment", "DimSize",
                          "ElementType", "BinaryData", "HeaderSize"}) {
    const std::string_view rest = std::string_view(head).substr(i);
    if (starts_with(rest, key)) {
      const std::string_view after = detail::trim(rest.substr(std::strlen(key), 8));
      if (!after.empty() && after.front() == '=') return Fmt::metaimage;
    }
  }
  return Fmt::unknown;
}

Volume dispatch(Fmt f, const std::string& path, const RawOptions& raw) {
  switch (f) {
    case Fmt::nrrd: return detail::read_nrrd(path);
    case Fmt::metaimage: return detail::read_metaimage(path);
    case Fmt::nifti: return detail::read_nifti(path);
    case Fmt::vtk: return detail::read_vtk_legacy(path);
    case Fmt::vti: return detail::read_vti(path);
    case Fmt::slc: return detail::read_slc(path);
    case Fmt::mrc: return detail::read_mrc(path);
    case Fmt::raw: return detail::read_raw(path, raw);
    case Fmt::unknown: break;
  }
  fail(Status::internal, path + ": no reader for this format");
}

/// DICOM: a directory (unless named like another format: "x.nrrd/" is a mistake, reported as
/// "is a directory"), a `.dcm` file, or a file with the Part 10 preamble whose extension names no
/// other format (a `.mha` with "DICM" at byte 128 is read as MetaImage: found by fuzzing, where
/// such files reached GDCM from every volume reader's target).
bool is_dicom_input(const std::string& path, const std::string& ext) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return from_extension(ext) == Fmt::unknown;
  if (ext == ".dcm") return true;
  return from_extension(ext) == Fmt::unknown && detail::is_dicom_file(path);
}

}  // namespace

Volume read_dicom_series(const std::vector<std::string>& files, const std::string& series_uid) {
  const std::string where = files.empty() ? std::string("DICOM series") : files.front() + " (and " +
                                std::to_string(files.size() - 1) + " more files)";
  if (files.empty()) fail_input(where, "no files given");
  Volume v = detail::read_dicom_series(files, where, series_uid);
  v.source = files.front();
  return v;
}

std::string volume_format_for(const std::string& path, const RawOptions& raw) {
  if (raw.dims) return "raw";
  if (is_dicom_input(path, detail::lower_extension(path))) return "DICOM";
  const std::string ext = detail::lower_extension(path);
  Fmt f = from_extension(ext);
  bool nifti2 = false;
  std::string head;
  try {
    const InputFile file(path);
    head = file.read_string(0, 1024);
  } catch (const Error&) {
    // Unreadable: answer from the extension alone.
  }
  const bool gz = ext.size() > 3 && ext.compare(ext.size() - 3, 3, ".gz") == 0;
  const Fmt sniffed = (gz || head.empty()) ? Fmt::unknown : sniff(head, &nifti2);
  if (f == Fmt::unknown) f = sniffed;
  if (f == Fmt::nifti && gz && !head.empty()) {  // NIfTI-1 or -2: the first header word says
    try {
      const InputFile file(path);
      detail::InflateReader r(file, 0, file.size(), detail::ZWrap::gzip);
      std::string first(4, '\0');
      r.read_exact(first.data(), 4, "header");
      nifti2 = int32_at(first, 0, false) == 540 || int32_at(first, 0, true) == 540;
    } catch (const Error&) {
      // Corrupt stream: read_volume() will say so; the extension decides here.
    }
  }
  if (f == Fmt::nifti && nifti2) return "NIfTI-2";
  return format_name(f);
}

Volume read_volume(const std::string& path, const RawOptions& raw) {
  if (raw.dims) {
    Volume v = detail::read_raw(path, raw);
    check_world_range(v.grid, path);
    v.source = path;
    return v;
  }
  const std::string ext = detail::lower_extension(path);
  if (is_dicom_input(path, ext)) {
    Volume v = detail::read_dicom(path, raw.dicom_series);
    v.source = path;
    return v;
  }
  const Fmt by_ext = from_extension(ext);
  std::string head;
  {
    const InputFile file(path);  // missing / unreadable / not a file
    if (file.size() == 0) fail_input(path, "file is empty");
    head = file.read_string(0, 1024);
  }
  const bool gz = ext.size() > 3 && ext.compare(ext.size() - 3, 3, ".gz") == 0;
  const bool data_only = ext == ".img" || ext == ".img.gz" || by_ext == Fmt::raw;
  const Fmt sniffed = gz ? Fmt::unknown : sniff(head);
  Fmt f = by_ext;
  if (f == Fmt::unknown) {
    if (sniffed == Fmt::unknown)
      fail(Status::unsupported,
           path + ": unknown volume format (extension '" + ext +
               "' not recognised, no known magic); headerless raw data needs --dims and --type");
    f = sniffed;
  } else if (!data_only && sniffed != Fmt::unknown && sniffed != f) {
    fail_input(path, std::string("the extension says ") + format_name(f) +
                         " but the content is " + format_name(sniffed));
  }
  Volume v = dispatch(f, path, raw);
  check_world_range(v.grid, path);
  v.source = path;
  return v;
}

}  // namespace adamesh

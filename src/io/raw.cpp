// Headerless raw volumes: the caller supplies the geometry (RawOptions, from the CLI's
// --dims X,Y,Z --type T [--spacing] [--origin] [--endian] [--header-bytes]). Samples are x
// fastest, then y, then z. The file size must be exactly header_bytes + dims product × type
// size: a mismatch means the options do not describe the file.
#include <cmath>
#include <sstream>

#include "adamesh/error.h"
#include "io_util.h"
#include "volume_readers.h"

namespace adamesh::detail {

Volume read_raw(const std::string& path, const RawOptions& raw) {
  if (!raw.dims && !raw.type)
    fail_input(path, "headerless raw data needs --dims X,Y,Z and --type T (both missing)");
  if (!raw.dims) fail_input(path, "headerless raw data needs --dims X,Y,Z (missing)");
  if (!raw.type) fail_input(path, "headerless raw data needs --type T (missing)");
  for (int a = 0; a < 3; ++a) {
    if (!(std::isfinite(raw.spacing[a]) && raw.spacing[a] > 0))
      fail_input(path, "invalid --spacing " + format_number(raw.spacing[a]) + " (must be > 0)");
    if (!std::isfinite(raw.origin[a]))
      fail_input(path, "invalid --origin " + format_number(raw.origin[a]));
  }
  Grid grid;
  grid.dims = *raw.dims;
  grid.spacing = raw.spacing;
  grid.origin = raw.origin;
  const std::size_t bytes = checked_volume_bytes(grid.dims, *raw.type, path);

  const InputFile f(path);
  const std::uint64_t need = raw.header_bytes + bytes;
  if (raw.header_bytes > f.size() || f.size() != need) {
    std::ostringstream os;
    os << "size mismatch: --dims " << format_dims(grid.dims) << " of " << to_string(*raw.type);
    if (raw.header_bytes) os << " after " << raw.header_bytes << " header bytes";
    os << " need " << need << " bytes but the file has " << f.size() << " (file is "
       << (f.size() > need ? "larger" : "smaller") << ")";
    fail_input(path, os.str());
  }
  Volume v = allocate_volume(grid, *raw.type, path);
  v.format = "raw";
  f.read_exact(raw.header_bytes, v.data.data(), bytes, "sample data");
  fix_byte_order(v, raw.big_endian);
  return v;
}

}  // namespace adamesh::detail

// VolVis SLC reader (.slc), following the VolVis 2.1 slice file description and VTK's
// vtkSLCReader.
//
// ASCII header: magic 11111, x y z sizes, bits per voxel (8), x y z spacing, then units,
// data origin, data modification and compression (0 raw, 1 run-length encoded). Then an icon:
// "width height X" and three width×height planes (R, G, B), skipped. Then per slice:
// compression 0: x·y bytes; compression 1: "<size> X" and <size> RLE bytes, where a byte
// with bit 7 set starts a literal run of (byte & 0x7f) bytes and otherwise the next byte is
// repeated (byte & 0x7f) times; a count of 0 ends the slice. Quirk of real files: embryo.slc
// decodes to x·y − 1 voxels per slice; a slice short by less than one row is padded with 0
// (as tools/volread.py does), a shorter one, or one that decodes to more than x·y voxels, is an
// error. Origin 0, identity direction.
#include <cmath>
#include <cstring>
#include <sstream>

#include "adamesh/error.h"
#include "io_util.h"
#include "volume_readers.h"

namespace adamesh::detail {
namespace {

// Whitespace-separated ASCII tokens between binary blocks.
class Tokens {
 public:
  explicit Tokens(const InputFile& f) : f_(f) {}
  std::string next(const char* what) {
    skip_space();
    std::string tok;
    for (;;) {
      const char c = peek();
      if (c == '\0' || std::isspace(static_cast<unsigned char>(c))) break;
      tok.push_back(c);
      ++pos_;
      if (tok.size() > 64) fail_input(f_.path(), std::string("malformed header: overlong ") + what);
    }
    if (tok.empty()) fail_input(f_.path(), std::string("truncated header: missing ") + what);
    return tok;
  }
  void expect_x(const char* what) {
    skip_space();
    if (peek() != 'X') fail_input(f_.path(), std::string("malformed file: expected 'X' after ") + what);
    ++pos_;
  }
  std::uint64_t pos() const { return pos_; }
  void seek(std::uint64_t p) { pos_ = p; }

 private:
  char peek() {
    if (pos_ < buf_start_ || pos_ >= buf_start_ + buf_.size()) {
      buf_start_ = pos_;
      buf_ = f_.read_string(pos_, 256);
    }
    return pos_ - buf_start_ < buf_.size() ? buf_[pos_ - buf_start_] : '\0';
  }
  void skip_space() {
    while (std::isspace(static_cast<unsigned char>(peek())) && pos_ < f_.size()) ++pos_;
  }
  const InputFile& f_;
  std::uint64_t pos_ = 0, buf_start_ = 0;
  std::string buf_;
};

// Decodes one RLE slice into out (capacity n); returns the number of voxels produced.
std::size_t decode_rle(const std::string& path, std::int64_t slice, const std::uint8_t* in,
                       std::size_t in_len, std::uint8_t* out, std::size_t n) {
  std::size_t i = 0, o = 0;
  auto fail_slice = [&](const std::string& what) {
    fail_input(path, "corrupt RLE data in slice " + std::to_string(slice) + ": " + what);
  };
  while (i < in_len) {
    const std::uint8_t c = in[i++];
    const std::size_t run = c & 0x7f;
    if (run == 0) break;
    if (o + run > n) fail_slice("it decodes to more than " + std::to_string(n) + " voxels");
    if (c & 0x80) {
      if (i + run > in_len) fail_slice("a literal run passes the end of the slice data");
      std::memcpy(out + o, in + i, run);
      i += run;
    } else {
      if (i >= in_len) fail_slice("a repeat run has no value byte");
      std::memset(out + o, in[i++], run);
    }
    o += run;
  }
  return o;
}

}  // namespace

Volume read_slc(const std::string& path) {
  const InputFile f(path);
  Tokens t(f);
  if (t.next("magic number") != "11111") fail_input(path, "not a VolVis SLC file (magic number 11111 missing)");
  Grid grid;
  for (int a = 0; a < 3; ++a) grid.dims[a] = parse_int(t.next("dimensions"), path, "dimensions");
  const std::int64_t bits = parse_int(t.next("bits per voxel"), path, "bits per voxel");
  for (int a = 0; a < 3; ++a) {
    const double s = parse_double(t.next("spacing"), path, "spacing");
    if (!std::isfinite(s) || s <= 0) fail_input(path, "invalid spacing " + format_number(s));
    grid.spacing[a] = s;
  }
  for (const char* what : {"units", "data origin", "data modification"}) parse_int(t.next(what), path, what);
  const std::int64_t compression = parse_int(t.next("compression"), path, "compression");
  if (bits != 8) fail(Status::unsupported, path + ": " + std::to_string(bits) + " bits per voxel: only 8 is supported");
  if (compression != 0 && compression != 1)
    fail(Status::unsupported, path + ": SLC compression " + std::to_string(compression) + " is not supported");
  const std::size_t bytes = checked_volume_bytes(grid.dims, ScalarType::u8, path);

  const std::int64_t iw = parse_int(t.next("icon width"), path, "icon width");
  const std::int64_t ih = parse_int(t.next("icon height"), path, "icon height");
  if (iw < 0 || ih < 0 || iw > (1 << 20) || ih > (1 << 20)) fail_input(path, "invalid icon size");
  t.expect_x("the icon size");
  const std::uint64_t icon = 3 * static_cast<std::uint64_t>(iw) * static_cast<std::uint64_t>(ih);
  require_range(f, t.pos(), icon, "icon");
  t.seek(t.pos() + icon);

  const std::size_t slice = static_cast<std::size_t>(grid.dims[0] * grid.dims[1]);
  const std::uint64_t rest = f.size() - t.pos();
  if (compression == 0) require_range(f, t.pos(), bytes, "sample data");
  else if (rest < (std::uint64_t(1) << 56) && rest * 64 < bytes)
    fail_input(path, "truncated data: " + std::to_string(rest) + " bytes of RLE data cannot hold " +
                         std::to_string(bytes) + " voxels");

  Volume v = allocate_volume(grid, ScalarType::u8, path);
  v.format = "VolVis SLC";
  auto* out = reinterpret_cast<std::uint8_t*>(v.data.data());
  if (compression == 0) {
    f.read_exact(t.pos(), out, bytes, "sample data");
    return v;
  }
  std::vector<std::uint8_t> packed;
  for (std::int64_t z = 0; z < grid.dims[2]; ++z) {
    const std::string what = "slice " + std::to_string(z) + " size";
    const std::int64_t size = parse_int(t.next(what.c_str()), path, what);
    t.expect_x(what.c_str());
    if (size < 0 || static_cast<std::uint64_t>(size) > f.size() - std::min(f.size(), t.pos()))
      fail_input(path, "truncated data: slice " + std::to_string(z) + " needs " + std::to_string(size) +
                           " bytes at offset " + std::to_string(t.pos()) + " but the file has " +
                           std::to_string(f.size()) + " bytes");
    packed.resize(static_cast<std::size_t>(size));
    f.read_exact(t.pos(), packed.data(), packed.size(), "slice data");
    t.seek(t.pos() + packed.size());
    std::uint8_t* dst = out + static_cast<std::size_t>(z) * slice;
    const std::size_t got = decode_rle(path, z, packed.data(), packed.size(), dst, slice);
    if (got < slice) {
      if (slice - got >= static_cast<std::size_t>(grid.dims[0]))
        fail_input(path, "slice " + std::to_string(z) + " decodes to only " + std::to_string(got) + " of " +
                             std::to_string(slice) + " voxels");
      std::memset(dst + got, 0, slice - got);  // embryo.slc quirk: pad the missing tail with 0
    }
  }
  return v;
}

}  // namespace adamesh::detail

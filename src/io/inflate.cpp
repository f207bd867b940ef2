// zlib/gzip inflation for the readers in src/io (see io_util.h): a streaming reader over a
// file range and a one-shot in-memory variant, both with a hard limit on the output size.
#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <sstream>

#include "io_util.h"

namespace adamesh::detail {

namespace {

int window_bits(ZWrap w) {
  switch (w) {
    case ZWrap::zlib: return 15;
    case ZWrap::gzip: return 15 + 16;
    case ZWrap::automatic: break;
  }
  return 15 + 32;
}

[[noreturn]] void fail_corrupt(const std::string& where, const z_stream& s, int code) {
  std::string msg = "corrupt compressed data";
  if (s.msg) msg += std::string(": ") + s.msg;
  else if (code == Z_NEED_DICT) msg += ": needs a preset dictionary";
  fail_input(where, msg);
}

constexpr std::size_t kChunk = std::size_t(1) << 18;  // 256 KiB of compressed input at a time
constexpr uInt kMaxAvail = std::numeric_limits<uInt>::max();

}  // namespace

struct InflateReader::Impl {
  const InputFile& file;
  std::uint64_t next_offset, remaining;  // unread part of the file range
  ZWrap wrap;
  z_stream strm{};
  std::vector<std::uint8_t> buf;
  bool finished = false;
  std::uint64_t total = 0;

  Impl(const InputFile& f, std::uint64_t off, std::uint64_t len, ZWrap w)
      : file(f), next_offset(off), remaining(len), wrap(w), buf(kChunk) {
    if (inflateInit2(&strm, window_bits(w)) != Z_OK) fail_input(f.path(), "cannot initialise zlib");
    strm.next_in = buf.data();
    strm.avail_in = 0;
  }
  ~Impl() { inflateEnd(&strm); }

  // Moves unread input to the front of the buffer and tops it up from the file.
  void refill() {
    const std::size_t keep = strm.avail_in;
    if (keep > 0 && strm.next_in != buf.data()) std::memmove(buf.data(), strm.next_in, keep);
    const std::size_t want =
        static_cast<std::size_t>(std::min<std::uint64_t>(buf.size() - keep, remaining));
    const std::size_t got = want ? file.read_some(next_offset, buf.data() + keep, want) : 0;
    if (got < want) remaining = got;  // the file is shorter than the range: treat as its end
    next_offset += got;
    remaining -= std::min<std::uint64_t>(remaining, got);
    strm.next_in = buf.data();
    strm.avail_in = static_cast<uInt>(keep + got);
  }

  // After a stream end: another gzip member follows? (gzip files may be concatenated)
  bool next_member() {
    if (wrap == ZWrap::zlib) return false;
    if (strm.avail_in < 2 && remaining > 0) refill();
    if (strm.avail_in < 2 || strm.next_in[0] != 0x1f || strm.next_in[1] != 0x8b) return false;
    inflateReset(&strm);
    return true;
  }

  std::size_t read(std::uint8_t* dst, std::size_t n) {
    std::size_t produced = 0;
    while (produced < n && !finished) {
      if (strm.avail_in == 0) {
        refill();
        if (strm.avail_in == 0) {
          std::ostringstream os;
          os << "truncated compressed data: the stream ends after " << total + produced
             << " decompressed bytes";
          fail_input(file.path(), os.str());
        }
      }
      const uInt avail = static_cast<uInt>(std::min<std::size_t>(n - produced, kMaxAvail));
      strm.next_out = dst + produced;
      strm.avail_out = avail;
      const int r = inflate(&strm, Z_NO_FLUSH);
      produced += avail - strm.avail_out;
      if (r == Z_STREAM_END) {
        if (!next_member()) finished = true;
      } else if (r == Z_BUF_ERROR) {
        if (strm.avail_in != 0) fail_corrupt(file.path(), strm, r);  // no progress possible
      } else if (r != Z_OK) {
        fail_corrupt(file.path(), strm, r);
      }
    }
    total += produced;
    return produced;
  }
};

InflateReader::InflateReader(const InputFile& file, std::uint64_t offset, std::uint64_t length,
                             ZWrap wrap)
    : impl_(new Impl(file, offset, length, wrap)) {}

InflateReader::~InflateReader() { delete impl_; }

std::size_t InflateReader::read(void* dst, std::size_t n) {
  return impl_->read(static_cast<std::uint8_t*>(dst), n);
}

void InflateReader::read_exact(void* dst, std::size_t n, const char* what) {
  const std::uint64_t before = impl_->total;
  if (read(dst, n) != n) {
    std::ostringstream os;
    os << "truncated compressed data: " << what << " needs " << n << " bytes, the stream ends after "
       << impl_->total - before;
    fail_input(impl_->file.path(), os.str());
  }
}

void InflateReader::skip(std::uint64_t n, const char* what) {
  std::vector<std::uint8_t> scratch(static_cast<std::size_t>(std::min<std::uint64_t>(n, kChunk)));
  while (n > 0) {
    const std::size_t step = static_cast<std::size_t>(std::min<std::uint64_t>(n, scratch.size()));
    read_exact(scratch.data(), step, what);
    n -= step;
  }
}

void InflateReader::expect_end(std::uint64_t expected_total) {
  std::uint8_t extra = 0;
  if (read(&extra, 1) != 0) {
    std::ostringstream os;
    os << "decompressed data is larger than expected (more than " << expected_total << " bytes)";
    fail_input(impl_->file.path(), os.str());
  }
}

std::uint64_t InflateReader::total_out() const noexcept { return impl_->total; }

void inflate_buffer(const std::uint8_t* src, std::size_t src_len, void* dst, std::size_t n,
                    ZWrap wrap, const std::string& where) {
  z_stream s{};
  if (inflateInit2(&s, window_bits(wrap)) != Z_OK) fail_input(where, "cannot initialise zlib");
  struct Guard {
    z_stream* s;
    ~Guard() { inflateEnd(s); }
  } guard{&s};
  auto* out = static_cast<std::uint8_t*>(dst);
  std::size_t in_used = 0, out_used = 0;
  std::uint8_t scratch = 0;
  for (;;) {
    if (s.avail_in == 0 && in_used < src_len) {
      const std::size_t step = std::min<std::size_t>(src_len - in_used, kMaxAvail);
      s.next_in = const_cast<std::uint8_t*>(src + in_used);
      s.avail_in = static_cast<uInt>(step);
      in_used += step;
    }
    const bool probe = out_used == n;  // all expected output made: does the stream have more?
    const uInt avail =
        probe ? 1u : static_cast<uInt>(std::min<std::size_t>(n - out_used, kMaxAvail));
    s.next_out = probe ? &scratch : out + out_used;
    s.avail_out = avail;
    const uInt in_before = s.avail_in;
    const int r = inflate(&s, Z_NO_FLUSH);
    const uInt made = avail - s.avail_out;
    if (probe && made > 0) {
      std::ostringstream os;
      os << "decompressed data is larger than expected (more than " << n << " bytes)";
      fail_input(where, os.str());
    }
    if (!probe) out_used += made;
    if (r == Z_STREAM_END) break;
    if (r != Z_OK && r != Z_BUF_ERROR) fail_corrupt(where, s, r);
    if (made == 0 && s.avail_in == in_before) {  // no progress
      if (s.avail_in == 0 && in_used == src_len) {
        std::ostringstream os;
        os << "truncated compressed data: the stream ends after " << out_used << " of " << n
           << " bytes";
        fail_input(where, os.str());
      }
      fail_corrupt(where, s, r);
    }
  }
  if (out_used != n) {
    std::ostringstream os;
    os << "decompressed data is shorter than expected: " << out_used << " of " << n << " bytes";
    fail_input(where, os.str());
  }
}

}  // namespace adamesh::detail

// Helpers shared by the file readers in src/io (see io_util.h).
#include "io_util.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>

namespace adamesh::detail {

std::string lower_extension(const std::string& path) {
  std::string name = std::filesystem::path(path).filename().string();
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  auto ext_of = [](const std::string& n) {
    const auto dot = n.find_last_of('.');
    return dot == std::string::npos ? std::string() : n.substr(dot);
  };
  std::string ext = ext_of(name);
  if (ext == ".gz") ext = ext_of(name.substr(0, name.size() - 3)) + ext;
  return ext;
}

// ------------------------------------------------------------------------------------ files

InputFile::InputFile(const std::string& path) : path_(path) {
  // O_NONBLOCK: opening a FIFO must not wait for a writer; it is rejected below.
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd_ < 0) {
    const int err = errno;
    if (err == ENOENT) fail_input(path, "file not found");
    fail_input(path, std::string("cannot open: ") + std::strerror(err));
  }
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    const bool dir = S_ISDIR(st.st_mode);
    ::close(fd_);
    fd_ = -1;
    fail_input(path, dir ? "is a directory, not a file" : "not a regular file");
  }
  size_ = static_cast<std::uint64_t>(st.st_size);
}

InputFile::~InputFile() {
  if (fd_ >= 0) ::close(fd_);
}

std::size_t InputFile::read_some(std::uint64_t offset, void* dst, std::size_t n) const {
  std::size_t done = 0;
  auto* out = static_cast<char*>(dst);
  while (done < n) {
    const std::size_t want = std::min<std::size_t>(n - done, std::size_t(1) << 30);
    const ssize_t got = ::pread(fd_, out + done, want, static_cast<off_t>(offset + done));
    if (got < 0) {
      if (errno == EINTR) continue;
      fail_input(path_, std::string("read error: ") + std::strerror(errno));
    }
    if (got == 0) break;
    done += static_cast<std::size_t>(got);
  }
  return done;
}

void InputFile::read_exact(std::uint64_t offset, void* dst, std::size_t n, const char* what) const {
  require_range(*this, offset, n, what);
  if (read_some(offset, dst, n) != n)
    fail_input(path_, std::string("truncated ") + what + ": the file shrank while reading");
}

std::string InputFile::read_string(std::uint64_t offset, std::size_t max_bytes) const {
  if (offset >= size_) return {};
  std::string s(static_cast<std::size_t>(std::min<std::uint64_t>(max_bytes, size_ - offset)), '\0');
  s.resize(read_some(offset, s.data(), s.size()));
  return s;
}

void require_range(const InputFile& f, std::uint64_t offset, std::uint64_t bytes, const char* what) {
  if (offset > f.size() || bytes > f.size() - offset) {
    std::ostringstream os;
    os << "truncated " << what << ": expected " << bytes << " bytes at offset " << offset
       << " but the file has " << f.size() << " bytes";
    fail_input(f.path(), os.str());
  }
}

std::string resolve_relative(const std::string& header_path, const std::string& name) {
  const std::filesystem::path p(name);
  // A header names its data, so an untrusted header could otherwise make adamesh mesh any file
  // the user can read (/etc/passwd): data files must lie in the header's folder or below it.
  const std::filesystem::path norm = p.lexically_normal();
  if (name.empty() || p.is_absolute() || p.has_root_name() ||
      (!norm.empty() && *norm.begin() == ".."))
    fail_input(header_path, "data file '" + name +
                                "' is outside the header's folder (adamesh reads detached data "
                                "only from the header's folder or below)");
  const std::filesystem::path dir = std::filesystem::path(header_path).parent_path();
  return dir.empty() ? name : (dir / p).string();
}

// ----------------------------------------------------------------------------------- samples

bool host_is_little_endian() noexcept {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

void swap_bytes_in_place(void* data, std::size_t count, std::size_t elem_size) noexcept {
  auto* p = static_cast<std::uint8_t*>(data);
  switch (elem_size) {
    case 2:
      for (std::size_t i = 0; i < count; ++i, p += 2) {
        std::uint16_t v;
        std::memcpy(&v, p, 2);
        v = __builtin_bswap16(v);
        std::memcpy(p, &v, 2);
      }
      return;
    case 4:
      for (std::size_t i = 0; i < count; ++i, p += 4) {
        std::uint32_t v;
        std::memcpy(&v, p, 4);
        v = __builtin_bswap32(v);
        std::memcpy(p, &v, 4);
      }
      return;
    case 8:
      for (std::size_t i = 0; i < count; ++i, p += 8) {
        std::uint64_t v;
        std::memcpy(&v, p, 8);
        v = __builtin_bswap64(v);
        std::memcpy(p, &v, 8);
      }
      return;
    default:
      for (std::size_t i = 0; i < count; ++i, p += elem_size) std::reverse(p, p + elem_size);
  }
}

void fix_byte_order(Volume& v, bool data_big_endian) noexcept {
  const std::size_t sz = scalar_size(v.type);
  if (sz > 1 && data_big_endian == host_is_little_endian())
    swap_bytes_in_place(v.data.data(), v.data.size() / sz, sz);
}

namespace {
bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}
}  // namespace

AsciiSampleParser::AsciiSampleParser(ScalarType type, void* dst, std::size_t count,
                                     std::string where)
    : type_(type), dst_(static_cast<std::byte*>(dst)), count_(count), where_(std::move(where)) {}

void AsciiSampleParser::store(std::string_view tok) {
  const std::size_t index = parsed_;
  auto bad = [&](const char* problem) {
    std::ostringstream os;
    os << problem << " '" << std::string(tok.substr(0, 40)) << "' at sample " << index;
    fail_input(where_, os.str());
  };
  std::string_view t = tok;
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  dispatch_scalar(type_, [&](auto zero) {
    using T = decltype(zero);
    T value{};
    if constexpr (std::is_integral_v<T>) {
      std::int64_t iv = 0;
      auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), iv);
      if (ec != std::errc() || p != t.data() + t.size()) {
        double d = 0;
        auto [q, ec2] = std::from_chars(t.data(), t.data() + t.size(), d);
        if (ec2 != std::errc() || q != t.data() + t.size() || !std::isfinite(d)) bad("non-numeric value");
        if (d != std::floor(d) || d < -9.3e18 || d > 9.3e18) bad("non-integer value");
        iv = static_cast<std::int64_t>(d);
      }
      if (iv < static_cast<std::int64_t>(std::numeric_limits<T>::min()) ||
          iv > static_cast<std::int64_t>(std::numeric_limits<T>::max())) {
        std::ostringstream os;
        os << "value out of range for " << to_string(type_);
        bad(os.str().c_str());
      }
      value = static_cast<T>(iv);
    } else {
      double d = 0;
      auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), d);
      // Out-of-range magnitudes (ec == result_out_of_range) become ±inf/0 like strtod.
      if (p != t.data() + t.size() || (ec != std::errc() && ec != std::errc::result_out_of_range))
        bad("non-numeric value");
      if (ec == std::errc::result_out_of_range) d = std::strtod(std::string(t).c_str(), nullptr);
      value = static_cast<T>(d);
    }
    std::memcpy(dst_ + index * sizeof(T), &value, sizeof(T));
  });
  ++parsed_;
}

void AsciiSampleParser::feed(std::string_view text) {
  std::size_t i = 0;
  const std::size_t n = text.size();
  while (i < n && parsed_ < count_) {
    if (is_space(text[i])) {
      if (!pending_.empty()) {
        store(pending_);
        pending_.clear();
        if (parsed_ == count_) end_offset_ = fed_ + i;
      }
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < n && !is_space(text[j])) ++j;
    if (pending_.size() + (j - i) > 256) fail_input(where_, "overlong token in ASCII sample data");
    if (j == n) {  // token may continue in the next chunk
      pending_.append(text.substr(i, j - i));
    } else if (pending_.empty()) {
      store(text.substr(i, j - i));
      if (parsed_ == count_) end_offset_ = fed_ + j;
    } else {
      pending_.append(text.substr(i, j - i));
      store(pending_);
      pending_.clear();
      if (parsed_ == count_) end_offset_ = fed_ + j;
    }
    i = j;
  }
  fed_ += n;
}

void AsciiSampleParser::finish(const char* what) {
  if (!pending_.empty() && parsed_ < count_) {
    store(pending_);
    pending_.clear();
    end_offset_ = fed_;
  }
  if (parsed_ != count_) {
    std::ostringstream os;
    os << "truncated " << what << ": found " << parsed_ << " of " << count_ << " ASCII values";
    fail_input(where_, os.str());
  }
}

std::uint64_t read_ascii_samples(const InputFile& f, std::uint64_t offset, ScalarType type,
                                 void* dst, std::size_t count, const char* what) {
  AsciiSampleParser parser(type, dst, count, f.path());
  std::uint64_t pos = offset;
  while (!parser.done() && pos < f.size()) {
    const std::string chunk = f.read_string(pos, std::size_t(1) << 20);
    if (chunk.empty()) break;
    parser.feed(chunk);
    pos += chunk.size();
  }
  parser.finish(what);
  return offset + parser.end_offset();
}

std::uint64_t skip_lines(const InputFile& f, std::uint64_t offset, std::int64_t n) {
  std::uint64_t pos = offset;
  std::int64_t seen = 0;
  while (seen < n) {
    const std::string chunk = f.read_string(pos, std::size_t(1) << 16);
    if (chunk.empty()) {
      fail_input(f.path(), "truncated data: the file ends before the " + std::to_string(n) +
                               " lines to skip ('line skip')");
    }
    for (std::size_t i = 0; i < chunk.size(); ++i) {
      if (chunk[i] == '\n' && ++seen == n) return pos + i + 1;
    }
    pos += chunk.size();
  }
  return pos;
}

namespace {

// Opens a piece's file and returns it with the offset after its line skip.
std::uint64_t open_piece(const std::string& header, const DataPiece& piece, DataEncoding enc,
                         std::optional<InputFile>& f) {
  std::error_code ec;
  if (piece.file != header && !std::filesystem::exists(piece.file, ec))
    fail_input(header, "data file '" + piece.file + "' not found");
  f.emplace(piece.file);
  std::uint64_t off = piece.start;
  if (piece.line_skip > 0) off = skip_lines(*f, off, piece.line_skip);
  if (piece.byte_skip < -1) fail_input(header, "invalid byte skip " + std::to_string(piece.byte_skip));
  if (piece.byte_skip == -1 && enc != DataEncoding::raw)
    fail(Status::unsupported, header + ": byte skip -1 (data at the end of the file) needs raw encoding");
  return off;
}

// Errors inside a detached data file name the header first: "<header>: data file <msg>".
template <class F>
void in_piece(const std::string& header, const DataPiece& piece, F&& f) {
  if (piece.file == header) return f();
  try {
    f();
  } catch (const Error& e) {
    const std::string msg = e.what();
    if (msg.rfind(header + ": ", 0) == 0) throw;
    throw Error(e.status(), header + ": data file " + msg);
  }
}

void check_piece(const std::string& header, const DataPiece& piece, DataEncoding enc,
                 ScalarType type, std::size_t bytes) {
  std::optional<InputFile> file;
  std::uint64_t off = open_piece(header, piece, enc, file);
  const InputFile& f = *file;
  switch (enc) {
    case DataEncoding::raw:
      if (piece.byte_skip > 0) off += static_cast<std::uint64_t>(piece.byte_skip);
      require_range(f, piece.byte_skip == -1 ? 0 : off, bytes, "sample data");
      return;
    case DataEncoding::ascii: {
      off += static_cast<std::uint64_t>(piece.byte_skip);
      const std::uint64_t values = bytes / scalar_size(type);
      if (off > f.size() || f.size() - off < values) {
        std::ostringstream os;
        os << "truncated ASCII sample data: " << values << " values cannot fit in "
           << (off > f.size() ? 0 : f.size() - off) << " bytes";
        fail_input(f.path(), os.str());
      }
      return;
    }
    case DataEncoding::gzip:
    case DataEncoding::zlib_or_gzip: {
      std::uint64_t avail = off < f.size() ? f.size() - off : 0;
      if (piece.compressed_bytes) avail = std::min(avail, *piece.compressed_bytes);
      if (avail == 0 || (avail < (std::uint64_t(1) << 52) && avail * 1100 + 1024 < bytes)) {
        std::ostringstream os;
        os << "truncated compressed data: " << avail << " bytes cannot inflate to the " << bytes
           << " bytes of samples";
        fail_input(f.path(), os.str());
      }
      return;
    }
  }
}

void read_piece(const std::string& header, const DataPiece& piece, DataEncoding enc,
                ScalarType type, std::byte* dst, std::size_t bytes) {
  std::optional<InputFile> file;
  std::uint64_t off = open_piece(header, piece, enc, file);
  const InputFile& f = *file;
  switch (enc) {
    case DataEncoding::raw: {
      if (piece.byte_skip == -1) {
        require_range(f, off, bytes, "sample data");
        off = f.size() - bytes;
      } else {
        off += static_cast<std::uint64_t>(piece.byte_skip);
      }
      f.read_exact(off, dst, bytes, "sample data");
      return;
    }
    case DataEncoding::gzip:
    case DataEncoding::zlib_or_gzip: {
      if (off >= f.size()) require_range(f, off, 1, "compressed data");
      std::uint64_t length = f.size() - off;
      if (piece.compressed_bytes) {
        require_range(f, off, *piece.compressed_bytes, "compressed data");
        length = *piece.compressed_bytes;
      }
      InflateReader r(f, off, length, ZWrap::automatic);  // zlib or gzip wrapper
      const auto skip = static_cast<std::uint64_t>(piece.byte_skip);
      r.skip(skip, "byte skip");
      r.read_exact(dst, bytes, "sample data");
      r.expect_end(skip + bytes);
      return;
    }
    case DataEncoding::ascii: {
      off += static_cast<std::uint64_t>(piece.byte_skip);
      read_ascii_samples(f, off, type, dst, bytes / scalar_size(type), "ASCII sample data");
      return;
    }
  }
}

}  // namespace

void check_data_piece(const std::string& header, const DataPiece& piece, DataEncoding enc,
                      ScalarType type, std::size_t bytes) {
  in_piece(header, piece, [&] { check_piece(header, piece, enc, type, bytes); });
}

void read_data_piece(const std::string& header, const DataPiece& piece, DataEncoding enc,
                     ScalarType type, std::byte* dst, std::size_t bytes) {
  in_piece(header, piece, [&] { read_piece(header, piece, enc, type, dst, bytes); });
}

// ------------------------------------------------------------------------------------ base64

namespace {
int b64_value(unsigned char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}
}  // namespace

Base64Decoder::Base64Decoder(std::string_view text, std::string where)
    : text_(text), where_(std::move(where)) {}

void Base64Decoder::seek(std::size_t pos) noexcept {
  pos_ = std::min(pos, text_.size());
  buf_len_ = buf_pos_ = 0;
}

bool Base64Decoder::next_byte(std::uint8_t& out) {
  if (buf_pos_ < buf_len_) {
    out = buf_[buf_pos_++];
    return true;
  }
  int vals[4];
  int nv = 0, pad = 0;
  while (pos_ < text_.size() && nv + pad < 4) {
    const unsigned char c = static_cast<unsigned char>(text_[pos_]);
    if (is_space(static_cast<char>(c))) {
      ++pos_;
      continue;
    }
    if (c == '=') {
      if (nv < 2) fail_input(where_, "bad base64 data: misplaced '=' at character " + std::to_string(pos_));
      ++pad;
      ++pos_;
      continue;
    }
    const int v = b64_value(c);
    if (v < 0 || pad > 0) {
      std::ostringstream os;
      os << "bad base64 data: invalid character ";
      if (std::isprint(c)) os << "'" << char(c) << "'";
      else os << "0x" << std::hex << int(c) << std::dec;
      os << " at character " << pos_;
      fail_input(where_, os.str());
    }
    vals[nv++] = v;
    ++pos_;
  }
  if (nv == 0) return false;
  if (nv == 1) fail_input(where_, "bad base64 data: incomplete final group");
  for (int k = nv; k < 4; ++k) vals[k] = 0;
  const std::uint32_t bits = (std::uint32_t(vals[0]) << 18) | (std::uint32_t(vals[1]) << 12) |
                             (std::uint32_t(vals[2]) << 6) | std::uint32_t(vals[3]);
  buf_[0] = std::uint8_t(bits >> 16);
  buf_[1] = std::uint8_t(bits >> 8);
  buf_[2] = std::uint8_t(bits);
  buf_len_ = nv - 1;
  buf_pos_ = 0;
  out = buf_[buf_pos_++];
  return true;
}

void Base64Decoder::read(void* dst, std::size_t n, const char* what) {
  auto* out = static_cast<std::uint8_t*>(dst);
  std::size_t i = 0;
  while (i < n) {
    // Fast path: whole groups of four plain characters.
    if (buf_pos_ == buf_len_ && n - i >= 3 && pos_ + 4 <= text_.size()) {
      const int a = b64_value(static_cast<unsigned char>(text_[pos_])),
                b = b64_value(static_cast<unsigned char>(text_[pos_ + 1])),
                c = b64_value(static_cast<unsigned char>(text_[pos_ + 2])),
                d = b64_value(static_cast<unsigned char>(text_[pos_ + 3]));
      if ((a | b | c | d) >= 0) {
        const std::uint32_t bits = (std::uint32_t(a) << 18) | (std::uint32_t(b) << 12) |
                                   (std::uint32_t(c) << 6) | std::uint32_t(d);
        out[i] = std::uint8_t(bits >> 16);
        out[i + 1] = std::uint8_t(bits >> 8);
        out[i + 2] = std::uint8_t(bits);
        i += 3;
        pos_ += 4;
        continue;
      }
    }
    if (!next_byte(out[i])) {
      std::ostringstream os;
      os << "truncated " << what << ": base64 data ends after " << i << " of " << n << " bytes";
      fail_input(where_, os.str());
    }
    ++i;
  }
}

// ------------------------------------------------------------------------------ header values

std::string_view trim(std::string_view s) noexcept {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

std::string to_lower(std::string_view s) {
  std::string r(s);
  for (char& c : r) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return r;
}

std::vector<std::string> split_ws(std::string_view s) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && is_space(s[i])) ++i;
    std::size_t j = i;
    while (j < s.size() && !is_space(s[j])) ++j;
    if (j > i) out.emplace_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

namespace {
[[noreturn]] void fail_value(std::string_view s, const std::string& where, const std::string& field,
                             const char* kind) {
  std::string shown(s.substr(0, 60));
  fail_input(where, std::string(kind) + " '" + shown + "' for " + field);
}
}  // namespace

std::int64_t parse_int(std::string_view s, const std::string& where, const std::string& field) {
  std::string_view t = trim(s);
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  std::int64_t v = 0;
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec == std::errc::result_out_of_range) fail_value(s, where, field, "out-of-range value");
  if (ec != std::errc() || p != t.data() + t.size() || t.empty())
    fail_value(s, where, field, "non-numeric value");
  return v;
}

double parse_double(std::string_view s, const std::string& where, const std::string& field) {
  std::string_view t = trim(s);
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  double v = 0;
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec != std::errc() || p != t.data() + t.size() || t.empty())
    fail_value(s, where, field, "non-numeric value");
  return v;
}

std::vector<double> parse_doubles(std::string_view s, std::size_t n, const std::string& where,
                                  const std::string& field) {
  const auto toks = split_ws(s);
  if (toks.size() != n) {
    std::ostringstream os;
    os << field << " needs " << n << " values, got " << toks.size() << " ('"
       << std::string(trim(s).substr(0, 60)) << "')";
    fail_input(where, os.str());
  }
  std::vector<double> out;
  for (const auto& t : toks) out.push_back(parse_double(t, where, field));
  return out;
}

std::vector<std::int64_t> parse_ints(std::string_view s, std::size_t n, const std::string& where,
                                     const std::string& field) {
  const auto toks = split_ws(s);
  if (toks.size() != n) {
    std::ostringstream os;
    os << field << " needs " << n << " values, got " << toks.size() << " ('"
       << std::string(trim(s).substr(0, 60)) << "')";
    fail_input(where, os.str());
  }
  std::vector<std::int64_t> out;
  for (const auto& t : toks) out.push_back(parse_int(t, where, field));
  return out;
}

std::string format_number(double v) {
  char buf[64];
  auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, p) : std::string("?");
}

std::string format_dims(const std::array<std::int64_t, 3>& d) {
  return std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" + std::to_string(d[2]);
}

std::string format_file_pattern(const std::string& pattern, std::int64_t value,
                                const std::string& where) {
  std::string out;
  int conversions = 0;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') {
      out.push_back(pattern[i]);
      continue;
    }
    if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
      out.push_back('%');
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    bool zero = false;
    if (j < pattern.size() && pattern[j] == '0') {
      zero = true;
      ++j;
    }
    int width = 0;
    while (j < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[j])) && width < 100)
      width = width * 10 + (pattern[j++] - '0');
    if (j >= pattern.size() || (pattern[j] != 'd' && pattern[j] != 'i' && pattern[j] != 'u') ||
        ++conversions > 1)
      fail_input(where, "unsupported data file pattern '" + pattern +
                            "' (expected one %d-style conversion)");
    // The magnitude in unsigned arithmetic: -INT64_MIN does not fit in an int64_t.
    const std::uint64_t magnitude =
        value < 0 ? std::uint64_t(0) - static_cast<std::uint64_t>(value) : static_cast<std::uint64_t>(value);
    std::string digits = std::to_string(magnitude);
    const std::size_t sign = value < 0 ? 1 : 0;
    std::string pad;
    if (digits.size() + sign < std::size_t(width)) pad.assign(width - digits.size() - sign, zero ? '0' : ' ');
    out += zero ? (std::string(sign, '-') + pad + digits) : (pad + std::string(sign, '-') + digits);
    i = j;
  }
  if (conversions != 1)
    fail_input(where, "data file pattern '" + pattern + "' has no %d-style conversion");
  return out;
}

std::vector<std::string> expand_file_pattern(const std::string& pattern, std::int64_t lo,
                                             std::int64_t hi, std::int64_t step,
                                             const std::string& where, const std::string& field) {
  constexpr std::uint64_t kMaxFiles = 1000000;
  const std::string range = std::to_string(lo) + " " + std::to_string(hi) + " " + std::to_string(step);
  if (step == 0 || (step > 0 && hi < lo) || (step < 0 && hi > lo))
    fail_input(where, "invalid " + field + " range '" + range + "'");
  // |hi - lo| and |step| as unsigned 64-bit values: exact for every pair of int64 values.
  const std::uint64_t span = hi >= lo ? static_cast<std::uint64_t>(hi) - static_cast<std::uint64_t>(lo)
                                      : static_cast<std::uint64_t>(lo) - static_cast<std::uint64_t>(hi);
  const std::uint64_t stride = step > 0 ? static_cast<std::uint64_t>(step)
                                        : std::uint64_t(0) - static_cast<std::uint64_t>(step);
  const std::uint64_t count = span / stride;  // files after the first
  if (count >= kMaxFiles)
    fail_input(where, field + " range '" + range + "' names more than 1000000 files");
  std::vector<std::string> names;
  names.reserve(static_cast<std::size_t>(count + 1));
  for (std::uint64_t k = 0; k <= count; ++k) {
    // lo + k*step stays between lo and hi, so the unsigned sum converts back exactly.
    const std::uint64_t offset = k * stride;
    const std::int64_t i = step > 0 ? static_cast<std::int64_t>(static_cast<std::uint64_t>(lo) + offset)
                                    : static_cast<std::int64_t>(static_cast<std::uint64_t>(lo) - offset);
    names.push_back(format_file_pattern(pattern, i, where));
  }
  return names;
}

void set_axes_from_vectors(Grid& g, const Vec3& a0, const Vec3& a1, const Vec3& a2,
                           const std::string& where, const std::string& what) {
  const Vec3 axes[3] = {a0, a1, a2};
  Vec3 unit[3];
  for (int a = 0; a < 3; ++a) {
    const double len = norm(axes[a]);
    if (!std::isfinite(len) || len <= 0)
      fail_input(where, what + ": axis " + std::to_string(a) + " has zero or non-finite length");
    g.spacing[a] = len;
    unit[a] = axes[a] / len;
  }
  g.direction = Mat3::from_columns(unit[0], unit[1], unit[2]);
  if (std::abs(g.direction.determinant()) < 1e-6)
    fail_input(where, what + ": the axis directions are degenerate (singular matrix)");
}

}  // namespace adamesh::detail

// Helpers shared by the file readers and writers in src/io: file access with size checks,
// zlib/gzip inflation with a hard output limit, in-place byte swapping, ASCII sample parsing,
// base64 decoding and header-line parsing. Every failure throws adamesh::Error with a one-line
// "<path>: <problem>" message.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "adamesh/error.h"
#include "adamesh/volume.h"

namespace adamesh::detail {

/// Lower-case extension including the dot, with ".gz" kept as part of it: "a.nii.gz" -> ".nii.gz".
std::string lower_extension(const std::string& path);

// ---------------------------------------------------------------------------------- files

/// A regular file opened for reading. Throws "<path>: file not found", "<path>: cannot open:
/// <reason>" or "<path>: not a regular file".
class InputFile {
 public:
  explicit InputFile(const std::string& path);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  const std::string& path() const noexcept { return path_; }
  std::uint64_t size() const noexcept { return size_; }

  /// Reads up to n bytes at `offset`; returns the count (short only at the end of the file).
  std::size_t read_some(std::uint64_t offset, void* dst, std::size_t n) const;
  /// Reads exactly n bytes at `offset`, or fails with "<path>: truncated <what>: ...".
  void read_exact(std::uint64_t offset, void* dst, std::size_t n, const char* what) const;
  /// Up to `max_bytes` bytes from `offset` (fewer at the end of the file).
  std::string read_string(std::uint64_t offset, std::size_t max_bytes) const;

 private:
  std::string path_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

/// Fails with "<path>: truncated data: ..." unless [offset, offset+bytes) lies inside the file.
void require_range(const InputFile& f, std::uint64_t offset, std::uint64_t bytes, const char* what);

/// `name` resolved against the directory of `header_path`. Fails (invalid input) when `name` is
/// absolute or leaves that directory through "..": a header may only name data beside or below it.
std::string resolve_relative(const std::string& header_path, const std::string& name);

// ---------------------------------------------------------------------------- compression

enum class ZWrap { zlib, gzip, automatic };

/// Streaming inflater over a byte range of a file. Concatenated gzip members are read as one
/// stream (as gzip(1) does); bytes after the last stream end are ignored.
class InflateReader {
 public:
  InflateReader(const InputFile& file, std::uint64_t offset, std::uint64_t length, ZWrap wrap);
  ~InflateReader();
  InflateReader(const InflateReader&) = delete;
  InflateReader& operator=(const InflateReader&) = delete;

  /// Decompresses up to n bytes into dst; returns fewer only at the end of the stream.
  std::size_t read(void* dst, std::size_t n);
  /// Reads exactly n bytes or fails with "<path>: truncated compressed data: ...".
  void read_exact(void* dst, std::size_t n, const char* what);
  /// Discards n decompressed bytes (same failure as read_exact).
  void skip(std::uint64_t n, const char* what);
  /// Fails with "<path>: decompressed data is larger than expected ..." unless the stream ends here.
  void expect_end(std::uint64_t expected_total);
  std::uint64_t total_out() const noexcept;

 private:
  struct Impl;
  Impl* impl_;
};

/// Inflates one complete zlib/gzip stream held in memory into exactly `n` bytes at dst; fails on
/// a corrupt stream, short output or output beyond n bytes. `where` prefixes messages.
void inflate_buffer(const std::uint8_t* src, std::size_t src_len, void* dst, std::size_t n,
                    ZWrap wrap, const std::string& where);

// ------------------------------------------------------------------------------- samples

bool host_is_little_endian() noexcept;
/// Reverses the bytes of each of `count` elements of `elem_size` bytes in place.
void swap_bytes_in_place(void* data, std::size_t count, std::size_t elem_size) noexcept;
/// Swaps when the data's byte order differs from the host's.
void fix_byte_order(Volume& v, bool data_big_endian) noexcept;

/// Incremental parser of whitespace-separated ASCII numbers into a typed sample array.
/// Integer types accept integral values only ("12", "12.0", "1.2e1") within the type's range.
class AsciiSampleParser {
 public:
  AsciiSampleParser(ScalarType type, void* dst, std::size_t count, std::string where);
  /// Consumes text; numbers may span calls. Text after the last needed value is ignored.
  void feed(std::string_view text);
  /// Flushes a pending token; fails unless `count` values were parsed.
  void finish(const char* what);
  bool done() const noexcept { return parsed_ == count_; }
  /// Offset (in the text fed so far) just past the last needed value; valid once done().
  std::uint64_t end_offset() const noexcept { return end_offset_; }

 private:
  void store(std::string_view token);
  ScalarType type_;
  std::byte* dst_;
  std::size_t count_;
  std::size_t parsed_ = 0;
  std::string where_;
  std::string pending_;
  std::uint64_t fed_ = 0, end_offset_ = 0;
};

/// Parses `count` ASCII samples of `type` from the file at `offset` into dst (streamed in
/// chunks, no full text copy). Returns the file offset just past the last sample.
std::uint64_t read_ascii_samples(const InputFile& f, std::uint64_t offset, ScalarType type,
                                 void* dst, std::size_t count, const char* what);

/// Offset just after the n-th newline at or after `offset` (fails if the file has fewer lines).
std::uint64_t skip_lines(const InputFile& f, std::uint64_t offset, std::int64_t n);

/// Base64 (RFC 4648) decoder that skips whitespace and accepts '=' padding in the middle (data
/// encoded in several pieces). Fails with "<where>: bad base64 data: ...".
class Base64Decoder {
 public:
  Base64Decoder(std::string_view text, std::string where);
  /// Decodes exactly n bytes into dst.
  void read(void* dst, std::size_t n, const char* what);
  /// Characters consumed so far (position in the text).
  std::size_t position() const noexcept { return pos_; }
  /// Moves to a character position, dropping partially decoded bytes.
  void seek(std::size_t pos) noexcept;

 private:
  bool next_byte(std::uint8_t& out);
  std::string_view text_;
  std::string where_;
  std::size_t pos_ = 0;
  std::uint8_t buf_[3] = {0, 0, 0};
  int buf_len_ = 0, buf_pos_ = 0;
};

// ----------------------------------------------------------------------- data pieces

enum class DataEncoding { raw, gzip, zlib_or_gzip, ascii };

/// One file (or the tail of the header file) holding `bytes` bytes of the sample array.
struct DataPiece {
  DataPiece() = default;
  explicit DataPiece(std::string f, std::uint64_t s = 0) : file(std::move(f)), start(s) {}
  std::string file;              ///< path of the file holding the data
  std::uint64_t start = 0;       ///< where the data section starts (after an attached header)
  std::int64_t line_skip = 0;    ///< lines to skip from `start` (in the file, before decoding)
  std::int64_t byte_skip = 0;    ///< bytes to skip after the lines; -1: data at the file's end
                                 ///< (raw only); compressed: skipped after decompression
  std::optional<std::uint64_t> compressed_bytes;  ///< length of the compressed stream if known
};

/// Reads `bytes` bytes of samples (type `type`, for ASCII) of one piece into dst. `header` is
/// the path named in messages about missing data files ("<header>: data file '...' not found").
/// Raw data must fit in the file before anything is read; compressed data must inflate to
/// exactly the expected size.
/// Cheap checks before the sample array is allocated: the data file exists, raw data fits in
/// it, ASCII data has at least one character per value and compressed data is not too short to
/// inflate to `bytes` (zlib's maximum ratio is about 1032:1).
void check_data_piece(const std::string& header, const DataPiece& piece, DataEncoding enc,
                      ScalarType type, std::size_t bytes);
void read_data_piece(const std::string& header, const DataPiece& piece, DataEncoding enc,
                     ScalarType type, std::byte* dst, std::size_t bytes);

// ------------------------------------------------------------------------- header values

std::string_view trim(std::string_view s) noexcept;
std::string to_lower(std::string_view s);
std::vector<std::string> split_ws(std::string_view s);
/// Parses the whole string as a number or fails: "<where>: non-numeric value 'x' for <field>".
std::int64_t parse_int(std::string_view s, const std::string& where, const std::string& field);
double parse_double(std::string_view s, const std::string& where, const std::string& field);
/// Exactly n whitespace-separated numbers (fails naming the field otherwise).
std::vector<double> parse_doubles(std::string_view s, std::size_t n, const std::string& where,
                                  const std::string& field);
std::vector<std::int64_t> parse_ints(std::string_view s, std::size_t n, const std::string& where,
                                     const std::string& field);
/// Formats a number like "%g" but with enough digits to be exact for file-format values.
std::string format_number(double v);
/// "64x64x93"
std::string format_dims(const std::array<std::int64_t, 3>& d);

/// Expands a printf-style file-name pattern with one integer conversion (%d, %i, %u with
/// optional '0' flag and width; "%%" is a literal '%'). Fails on any other conversion.
std::string format_file_pattern(const std::string& pattern, std::int64_t value,
                                const std::string& where);

/// The file names of a numbered data-file pattern "PATTERN LO HI STEP" (NRRD `data file`,
/// MetaImage `ElementDataFile`): LO, LO+STEP, ... up to HI inclusive. Fails (naming `field`)
/// on a zero step, a step pointing away from HI or more than 1,000,000 files; the arithmetic
/// cannot overflow for any 64-bit LO, HI, STEP.
std::vector<std::string> expand_file_pattern(const std::string& pattern, std::int64_t lo,
                                             std::int64_t hi, std::int64_t step,
                                             const std::string& where, const std::string& field);

/// Spacing / direction from the three world-space axis vectors (columns of index → world):
/// spacing = lengths, direction = normalised columns. Fails on a zero or non-finite vector or a
/// singular matrix, naming `what`.
void set_axes_from_vectors(Grid& g, const Vec3& a0, const Vec3& a1, const Vec3& a2,
                           const std::string& where, const std::string& what);

}  // namespace adamesh::detail

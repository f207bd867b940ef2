// Volumes: a regular grid of samples placed in world space.
//
// world position of sample (i, j, k) = origin + direction · (spacing ∘ (i, j, k))
//
// `direction` holds the world directions of the index axes as columns (unit vectors for
// well-formed files; any invertible matrix is accepted). Samples are stored once, in the file's
// own scalar type, x fastest then y then z (this is the single full-size working copy; readers
// decode straight into it, byte-swapping in place).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "adamesh/vec.h"

namespace adamesh {

enum class ScalarType : std::uint8_t { u8, i8, u16, i16, u32, i32, f32, f64 };

std::size_t scalar_size(ScalarType t) noexcept;
const char* to_string(ScalarType t) noexcept;  // "uint8", "int16", "float32", ...
/// Accepts the common spellings: uint8/uchar/unsigned char/u8, int16/short, float/float32, ...
std::optional<ScalarType> parse_scalar_type(std::string_view name);
bool is_floating(ScalarType t) noexcept;

/// Calls f(T{}) with T the C++ type of t; returns what f returns.
template <class F>
decltype(auto) dispatch_scalar(ScalarType t, F&& f) {
  switch (t) {
    case ScalarType::u8: return f(std::uint8_t{});
    case ScalarType::i8: return f(std::int8_t{});
    case ScalarType::u16: return f(std::uint16_t{});
    case ScalarType::i16: return f(std::int16_t{});
    case ScalarType::u32: return f(std::uint32_t{});
    case ScalarType::i32: return f(std::int32_t{});
    case ScalarType::f32: return f(float{});
    case ScalarType::f64: break;
  }
  return f(double{});
}

/// Geometry of the sampling lattice.
struct Grid {
  std::array<std::int64_t, 3> dims{0, 0, 0};  ///< samples along x, y, z
  Vec3 spacing{1, 1, 1};                       ///< world units per index step, > 0
  Vec3 origin{};                               ///< world position of sample (0,0,0)
  Mat3 direction{};                            ///< columns: world directions of i, j, k

  std::int64_t num_samples() const noexcept { return dims[0] * dims[1] * dims[2]; }
  std::int64_t linear_index(std::int64_t i, std::int64_t j, std::int64_t k) const noexcept {
    return i + dims[0] * (j + dims[1] * k);
  }
  /// direction · diag(spacing): maps index offsets to world offsets.
  Mat3 index_to_world_matrix() const noexcept;
  Vec3 to_world(const Vec3& ijk) const noexcept { return origin + index_to_world_matrix() * ijk; }
  /// Continuous index of a world point (inverse affine map).
  Vec3 to_index(const Vec3& p) const noexcept;
  /// Axis-aligned world bounding box of the eight corner samples.
  Box world_bounds() const noexcept;
  /// Smallest voxel edge length in world units.
  double min_spacing() const noexcept;
  /// True when direction is the identity (axis-aligned grid).
  bool axis_aligned() const noexcept;
  /// How far (index units, per index axis) a mesh's float vertex may lie off a face it is on:
  /// one float step of the grid's largest world coordinate, along each index axis.
  Vec3 float_rounding_in_index() const noexcept;
};

/// Largest world coordinate magnitude adamesh accepts (inputs, grids, hierarchies): meshes store
/// float coordinates and the metrics square lengths, so 1e18 keeps every squared length finite in
/// float (3.4e38). The smallest voxel edge accepted is 1e-18 (its square stays a normal float).
inline constexpr double kMaxWorldCoordinate = 1e18;
inline constexpr double kMinVoxelEdge = 1e-18;

/// Throws Error(invalid_input, "<where>: ...") unless every corner of the grid lies within
/// ±kMaxWorldCoordinate and every voxel edge is finite and at least kMinVoxelEdge long.
void check_world_range(const Grid& grid, const std::string& where);

/// Uninitialised, owned byte buffer (no zero-fill of large volumes), or borrowed memory kept
/// alive by its owner (the Python module's numpy arrays: no copy).
class SampleBuffer {
 public:
  SampleBuffer() = default;
  explicit SampleBuffer(std::size_t bytes);
  /// Borrows `bytes` bytes at `data`; `owner` keeps them alive as long as the buffer exists.
  SampleBuffer(std::byte* data, std::size_t bytes, std::shared_ptr<const void> owner) noexcept
      : owner_(std::move(owner)), ptr_(data), size_(bytes) {}
  SampleBuffer(SampleBuffer&& o) noexcept { *this = std::move(o); }
  SampleBuffer& operator=(SampleBuffer&& o) noexcept {
    data_ = std::move(o.data_);
    owner_ = std::move(o.owner_);
    ptr_ = std::exchange(o.ptr_, nullptr);
    size_ = std::exchange(o.size_, 0);
    return *this;
  }
  std::byte* data() noexcept { return ptr_; }
  const std::byte* data() const noexcept { return ptr_; }
  std::size_t size() const noexcept { return size_; }
  bool borrowed() const noexcept { return owner_ != nullptr; }

 private:
  std::unique_ptr<std::byte[]> data_;
  std::shared_ptr<const void> owner_;
  std::byte* ptr_ = nullptr;
  std::size_t size_ = 0;
};

struct Volume {
  Grid grid;
  ScalarType type = ScalarType::f32;  ///< storage type of the samples
  std::string format;                 ///< e.g. "NRRD", "MetaImage", "NIfTI-1", "implicit"
  std::string source;                 ///< the path or input spec it came from
  SampleBuffer data;

  template <class T>
  T* samples() noexcept { return reinterpret_cast<T*>(data.data()); }
  template <class T>
  const T* samples() const noexcept { return reinterpret_cast<const T*>(data.data()); }

  /// Sample at a linear index, converted to double (generic, not for hot loops).
  double at(std::int64_t linear) const noexcept;
  double at(std::int64_t i, std::int64_t j, std::int64_t k) const noexcept {
    return at(grid.linear_index(i, j, k));
  }
};

/// Validates dims (each ≥ 1, product and byte size without overflow, byte size below the memory
/// this machine has) and throws Error(invalid_input, "<where>: ...") otherwise.
/// Returns the byte size of the sample array.
std::size_t checked_volume_bytes(const std::array<std::int64_t, 3>& dims, ScalarType type,
                                 const std::string& where);

/// Allocates an uninitialised volume after checked_volume_bytes().
Volume allocate_volume(const Grid& grid, ScalarType type, const std::string& where);

/// Bytes of physical memory this process may use (MemAvailable, or physical pages).
std::uint64_t available_memory_bytes() noexcept;

}  // namespace adamesh

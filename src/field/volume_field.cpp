// Sampled scalar field: trilinear value and a continuous gradient (ALGORITHM.md 2.1).
//
// value(p):    world -> continuous index (Grid::to_index), clamped to [0, dims-1] per axis, then
//              trilinear interpolation of the 8 surrounding samples.
// gradient(p): central differences (s[i+1] - s[i-1]) / 2 at the 8 corner samples (one-sided
//              s[1]-s[0], s[n-1]-s[n-2] at the border, 0 along an axis with one sample), trilinearly
//              interpolated with the same weights, then mapped from index to world units with
//              (index_to_world_matrix)^-T (chain rule for f(p) = F(A^-1 (p - origin))).
// Nothing is precomputed per sample (no gradient volume): a query reads at most 48 samples.
// Each query dispatches once on the scalar type; the kernels are templated on T.
#include <algorithm>
#include <cmath>
#include <memory>

#include "adamesh/error.h"
#include "adamesh/field.h"

namespace adamesh {

namespace {

/// Cell of a continuous index: lower corner i[a], weights t[a] in [0,1], and the four clamped
/// indices idx[a][0..3] = clamp(i-1 .. i+2) used by the central differences.
struct Cell {
  std::int64_t idx[3][4];
  double t[3];
};

/// Along one axis of n samples: the clamped continuous index x's lower sample i (at most n − 2)
/// and its weight t in [0, 1].
std::int64_t lower_sample(std::int64_t n, double x, double& t) {
  if (!(x >= 0)) x = 0;  // also catches NaN
  if (x > double(n - 1)) x = double(n - 1);
  std::int64_t i = static_cast<std::int64_t>(std::floor(x));
  if (i > n - 2) i = std::max<std::int64_t>(n - 2, 0);
  t = std::min(1.0, x - double(i));
  return i;
}

Cell locate(const Grid& g, const Vec3& q) {
  Cell c;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t n = g.dims[a], i = lower_sample(n, q[a], c.t[a]);
    for (int d = 0; d < 4; ++d) c.idx[a][d] = std::clamp<std::int64_t>(i - 1 + d, 0, n - 1);
  }
  return c;
}

/// The two samples per axis that value() interpolates between and the weights: what locate()
/// computes without the outer indices of the central differences (value() is the hottest call
/// of the pipeline).
struct Corner {
  std::int64_t lo[3], hi[3];
  double t[3];
};

Corner locate_corner(const Grid& g, const Vec3& q) {
  Corner c;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t n = g.dims[a], i = lower_sample(n, q[a], c.t[a]);
    c.lo[a] = std::clamp<std::int64_t>(i, 0, n - 1);
    c.hi[a] = std::clamp<std::int64_t>(i + 1, 0, n - 1);
  }
  return c;
}

template <class T>
double trilinear(const T* s, const Grid& g, const Corner& c) {
  const std::int64_t sx = 1, sy = g.dims[0], sz = g.dims[0] * g.dims[1];
  const std::int64_t x0 = c.lo[0] * sx, x1 = c.hi[0] * sx;
  const std::int64_t y0 = c.lo[1] * sy, y1 = c.hi[1] * sy;
  const std::int64_t z0 = c.lo[2] * sz, z1 = c.hi[2] * sz;
  const double tx = c.t[0], ty = c.t[1], tz = c.t[2];
  auto at = [&](std::int64_t o) { return static_cast<double>(s[o]); };
  const double c00 = at(x0 + y0 + z0) + tx * (at(x1 + y0 + z0) - at(x0 + y0 + z0));
  const double c10 = at(x0 + y1 + z0) + tx * (at(x1 + y1 + z0) - at(x0 + y1 + z0));
  const double c01 = at(x0 + y0 + z1) + tx * (at(x1 + y0 + z1) - at(x0 + y0 + z1));
  const double c11 = at(x0 + y1 + z1) + tx * (at(x1 + y1 + z1) - at(x0 + y1 + z1));
  const double c0 = c00 + ty * (c10 - c00);
  const double c1 = c01 + ty * (c11 - c01);
  return c0 + tz * (c1 - c0);
}

/// Index-space gradient: per axis a, the difference quotient at each of the 8 corners, weighted
/// by the trilinear weights of the corner.
template <class T>
Vec3 index_gradient(const T* s, const Grid& g, const Cell& c) {
  const std::int64_t stride[3] = {1, g.dims[0], g.dims[0] * g.dims[1]};
  Vec3 grad;
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, e = (a + 2) % 3;
    double acc = 0;
    for (int da = 0; da < 2; ++da) {
      const std::int64_t plus = c.idx[a][da + 2], minus = c.idx[a][da];
      if (plus == minus) continue;
      const double wa = (da ? c.t[a] : 1 - c.t[a]) / double(plus - minus);
      for (int db = 0; db < 2; ++db) {
        const double wb = db ? c.t[b] : 1 - c.t[b];
        for (int de = 0; de < 2; ++de) {
          const double w = wa * wb * (de ? c.t[e] : 1 - c.t[e]);
          if (w == 0) continue;
          const std::int64_t base = c.idx[b][db + 1] * stride[b] + c.idx[e][de + 1] * stride[e];
          acc += w * (static_cast<double>(s[base + plus * stride[a]]) -
                      static_cast<double>(s[base + minus * stride[a]]));
        }
      }
    }
    grad[a] = acc;
  }
  return grad;
}

/// Index-space derivative of the trilinear interpolant itself (what `trilinear` computes); zero
/// along an axis where the continuous index was clamped (the field is constant there).
template <class T>
Vec3 interpolant_gradient(const T* s, const Grid& g, const Corner& c, const Vec3& q) {
  const std::int64_t stride[3] = {1, g.dims[0], g.dims[0] * g.dims[1]};
  Vec3 grad;
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, e = (a + 2) % 3;
    const std::int64_t hi = c.hi[a], lo = c.lo[a];
    if (hi == lo || !(q[a] >= 0) || q[a] > double(g.dims[a] - 1)) {
      grad[a] = 0;
      continue;
    }
    double acc = 0;
    for (int db = 0; db < 2; ++db) {
      const double wb = db ? c.t[b] : 1 - c.t[b];
      for (int de = 0; de < 2; ++de) {
        const double w = wb * (de ? c.t[e] : 1 - c.t[e]);
        const std::int64_t base = (db ? c.hi[b] : c.lo[b]) * stride[b] + (de ? c.hi[e] : c.lo[e]) * stride[e];
        acc += w * (static_cast<double>(s[base + hi * stride[a]]) -
                    static_cast<double>(s[base + lo * stride[a]]));
      }
    }
    grad[a] = acc;
  }
  return grad;
}

class VolumeField final : public ScalarField {
 public:
  VolumeField(const Volume& v, std::shared_ptr<const Volume> keep)
      : keep_(std::move(keep)), vol_(&v), grid_(v.grid) {
    const Mat3 a = grid_.index_to_world_matrix();
    if (!(std::abs(a.determinant()) > 0))
      fail_input(v.source.empty() ? "volume" : v.source, "singular index-to-world matrix");
    to_index_ = a.inverse();
    grad_to_world_ = to_index_.transposed();
    domain_ = grid_.world_bounds();
    if (grid_.num_samples() <= 0 || v.data.size() < std::size_t(grid_.num_samples()) * scalar_size(v.type))
      fail(Status::internal, "make_volume_field: sample buffer smaller than the grid");
  }

  double value(const Vec3& p) const override {
    const Corner c = locate_corner(grid_, to_index_ * (p - grid_.origin));
    return dispatch_scalar(vol_->type, [&](auto tag) {
      using T = decltype(tag);
      return trilinear(vol_->samples<T>(), grid_, c);
    });
  }

  Vec3 gradient(const Vec3& p) const override {
    const Cell c = locate(grid_, to_index_ * (p - grid_.origin));
    const Vec3 gi = dispatch_scalar(vol_->type, [&](auto tag) {
      using T = decltype(tag);
      return index_gradient(vol_->samples<T>(), grid_, c);
    });
    return grad_to_world_ * gi;
  }

  Box domain() const override { return domain_; }

  /// ∇ of the trilinear interpolant (value()'s exact derivative), world units.
  Vec3 exact_gradient(const Vec3& p) const {
    const Vec3 q = to_index_ * (p - grid_.origin);
    const Corner c = locate_corner(grid_, q);
    const Vec3 gi = dispatch_scalar(vol_->type, [&](auto tag) {
      using T = decltype(tag);
      return interpolant_gradient(vol_->samples<T>(), grid_, c, q);
    });
    return grad_to_world_ * gi;
  }

 private:
  std::shared_ptr<const Volume> keep_;  // null when the caller owns the volume
  const Volume* vol_;
  Grid grid_;
  Mat3 to_index_, grad_to_world_;
  Box domain_;
};

/// A volume field whose gradient is the exact derivative of its trilinear interpolant.
class InterpolantField final : public ScalarField {
 public:
  explicit InterpolantField(const VolumeField& f) : f_(f) {}
  double value(const Vec3& p) const override { return f_.value(p); }
  Vec3 gradient(const Vec3& p) const override { return f_.exact_gradient(p); }
  Box domain() const override { return f_.domain(); }

 private:
  const VolumeField& f_;
};

}  // namespace

std::unique_ptr<ScalarField> make_interpolant_gradient_field(const ScalarField& f, double h) {
  if (const auto* vf = dynamic_cast<const VolumeField*>(&f))
    return std::make_unique<InterpolantField>(*vf);
  return make_differenced_field(f, h);
}

std::unique_ptr<ScalarField> make_volume_field(const Volume& volume) {
  return std::make_unique<VolumeField>(volume, nullptr);
}

std::shared_ptr<const ScalarField> make_volume_field(std::shared_ptr<const Volume> volume) {
  if (!volume) fail(Status::internal, "make_volume_field: null volume");
  const Volume& v = *volume;
  return std::make_shared<VolumeField>(v, std::move(volume));
}

}  // namespace adamesh

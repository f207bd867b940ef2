// Small geometric helpers shared by the remesh passes (improve, fit, separate).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "adamesh/improve.h"
#include "adamesh/vec.h"

namespace adamesh::detail {

/// Smallest interior angle (radians) of triangle abc.
inline double smallest_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  auto at = [](const Vec3& o, const Vec3& u, const Vec3& w) {
    return std::atan2(norm(cross(u - o, w - o)), dot(u - o, w - o));
  };
  const double x = at(a, b, c), y = at(b, c, a);
  return std::max(0.0, std::min({x, y, std::numbers::pi - x - y}));
}

/// Eigenvectors of the symmetric 3×3 matrix a (row-major), as the columns of v, eigenvalues in
/// w, sorted by decreasing eigenvalue; v's columns form a right-handed frame. Cyclic Jacobi
/// sweeps (deterministic).
inline void symmetric_eigen(std::array<double, 9> a, std::array<double, 3>& w, std::array<Vec3, 3>& v) {
  std::array<double, 9> q = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int sweep = 0; sweep < 32; ++sweep) {
    const double off = a[1] * a[1] + a[2] * a[2] + a[5] * a[5];
    if (off <= 1e-30 * (a[0] * a[0] + a[4] * a[4] + a[8] * a[8]) || off == 0) break;
    for (int p = 0; p < 2; ++p)
      for (int r = p + 1; r < 3; ++r) {
        const double apr = a[3 * p + r];
        if (apr == 0) continue;
        const double theta = (a[3 * r + r] - a[3 * p + p]) / (2 * apr);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), sn = t * c;
        for (int k = 0; k < 3; ++k) {  // a = J^T a J
          const double akp = a[3 * k + p], akr = a[3 * k + r];
          a[3 * k + p] = c * akp - sn * akr;
          a[3 * k + r] = sn * akp + c * akr;
        }
        for (int k = 0; k < 3; ++k) {
          const double apk = a[3 * p + k], ark = a[3 * r + k];
          a[3 * p + k] = c * apk - sn * ark;
          a[3 * r + k] = sn * apk + c * ark;
        }
        for (int k = 0; k < 3; ++k) {
          const double qkp = q[3 * k + p], qkr = q[3 * k + r];
          q[3 * k + p] = c * qkp - sn * qkr;
          q[3 * k + r] = sn * qkp + c * qkr;
        }
      }
  }
  std::array<int, 3> idx = {0, 1, 2};
  std::sort(idx.begin(), idx.end(), [&](int x, int y) { return a[4 * x] > a[4 * y] || (a[4 * x] == a[4 * y] && x < y); });
  for (int i = 0; i < 3; ++i) {
    w[i] = a[4 * idx[i]];
    v[i] = Vec3{q[idx[i]], q[3 + idx[i]], q[6 + idx[i]]};
  }
  v[2] = cross(v[0], v[1]);
}

/// Where vertices may go: inside the volume's grid. Oblique grids (`faces` set): in index
/// space, within the float rounding of the faces; else the box widened to hold its faces as
/// floats (widened_to_floats); an empty box and no faces: anywhere.
class VolumeBounds {
 public:
  VolumeBounds() = default;
  VolumeBounds(const Box& box, const GridFaces& faces) : faces_(faces) {
    if (!faces.empty()) {
      oblique_ = bounded_ = true;
      for (int a = 0; a < 3; ++a) tol_[a] = faces.rounding[a] + 1e-9 * faces.extent[a];
    } else if (box.hi.x > box.lo.x) {
      bounded_ = true;
      box_ = widened_to_floats(box);
    }
  }
  bool contains(const Vec3& q) const {
    if (!bounded_) return true;
    if (oblique_) {
      const Vec3 u = faces_.to_index * (q - faces_.origin);
      for (int a = 0; a < 3; ++a)
        if (u[a] < -tol_[a] || u[a] > faces_.extent[a] + tol_[a]) return false;
      return true;
    }
    return q.x >= box_.lo.x && q.y >= box_.lo.y && q.z >= box_.lo.z && q.x <= box_.hi.x &&
           q.y <= box_.hi.y && q.z <= box_.hi.z;
  }

 private:
  GridFaces faces_;
  Box box_;
  std::array<double, 3> tol_{};
  bool bounded_ = false, oblique_ = false;
};

}  // namespace adamesh::detail

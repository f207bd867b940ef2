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

// Signed-distance estimate T_S(p) = (f(p) − iso)/|∇f(p)| and the safeguarded Newton projection
// F_S onto the iso-surface (ALGORITHM.md 2.1 and 2.9 step 4).
//
// project_to_iso, per step (at most opt.max_steps):
//   1. d = f(x) − iso, g = ∇f(x); with a plane constraint g is replaced by its in-plane part
//      g_t = g − (g·n)n, so the step stays in the plane and is the Newton step along g_t
//      (f(x + s g_t) ≈ d + s |g_t|²).
//   2. stop (converged) when |d|/|g| < tolerance; stop (flat) when |g| is zero, not finite, or the
//      Newton distance |d|/|g| exceeds kFlatDistance domain diagonals.
//   3. step = −d g/|g|², shortened to opt.max_step.
//   4. if f − iso changes sign between x and x + step, bisect that segment until the bracket is
//      shorter than tolerance/16 and continue from the bracket end with the smaller |f − iso|.
// The result is the iterate with the smallest |T_S| (the start point included), so it never has
// a larger residual than the start.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "adamesh/field.h"

namespace adamesh {

namespace {

constexpr double kFlatDistance = 1e6;  // Newton distances beyond this many domain diagonals = flat
constexpr int kMaxBisections = 60;

double residual_of(double d, const Vec3& g, double cap) {
  if (d == 0) return 0;
  if (std::isnan(d)) return std::numeric_limits<double>::infinity();
  const double gn = norm(g);
  if (!(gn > 0) || !std::isfinite(gn)) return cap;
  return std::min(std::abs(d) / gn, cap);
}

class DifferencedField final : public ScalarField {
 public:
  DifferencedField(const ScalarField& f, double h) : f_(f), h_(h) {}
  double value(const Vec3& p) const override { return f_.value(p); }
  Vec3 gradient(const Vec3& p) const override {
    Vec3 g;
    for (int k = 0; k < 3; ++k) {
      Vec3 e{};
      e[k] = h_;
      g[k] = (f_.value(p + e) - f_.value(p - e)) / (2 * h_);
    }
    return g;
  }
  Box domain() const override { return f_.domain(); }

 private:
  const ScalarField& f_;
  double h_;
};

}  // namespace

std::unique_ptr<ScalarField> make_differenced_field(const ScalarField& f, double h) {
  return std::make_unique<DifferencedField>(f, h);
}

double signed_distance(const ScalarField& f, double iso, const Vec3& p, double cap) {
  const double d = f.value(p) - iso;
  if (d == 0) return 0;
  if (std::isnan(d)) return d;
  return std::copysign(residual_of(d, f.gradient(p), cap), d);
}

ProjectResult project_to_iso(const ScalarField& f, double iso, const Vec3& p,
                             const ProjectOptions& opt) {
  const double cap = std::numeric_limits<double>::max();
  const double flat_distance = kFlatDistance * std::max(f.domain().diagonal(), opt.max_step);
  const Vec3 n = normalized(opt.plane_normal);
  const bool constrained = norm2(n) > 0;

  Vec3 x = p;
  double d = f.value(x) - iso;
  Vec3 gx = f.gradient(x);
  ProjectResult best{x, residual_of(d, gx, cap), 0, false, gx, 0};
  if (std::isfinite(d) && d != 0 && best.residual < cap) best.start_distance = std::copysign(best.residual, d);

  for (int step = 0; step < opt.max_steps; ++step) {
    if (!std::isfinite(d) || residual_of(d, gx, cap) < opt.tolerance) break;
    Vec3 g = gx;
    if (constrained) g -= dot(g, n) * n;
    const double g2 = norm2(g);
    if (!(g2 > 0) || !std::isfinite(g2) || std::abs(d) / std::sqrt(g2) > flat_distance) break;

    Vec3 delta = (-d / g2) * g;
    const double len = norm(delta);
    if (len > opt.max_step) delta *= opt.max_step / len;
    Vec3 y = x + delta;
    double dy = f.value(y) - iso;

    if ((d < 0 && dy > 0) || (d > 0 && dy < 0)) {
      // The crossing lies on [x, y]: bisect, a on the side of x, b on the side of y.
      Vec3 a = x, b = y;
      double da = d, db = dy;
      const double stop = opt.tolerance / 16;
      for (int it = 0; it < kMaxBisections && distance(a, b) > stop; ++it) {
        const Vec3 m = 0.5 * (a + b);
        const double dm = f.value(m) - iso;
        if (dm == 0) {
          a = b = m;
          da = db = 0;
          break;
        }
        if ((dm < 0) == (da < 0)) {
          a = m;
          da = dm;
        } else {
          b = m;
          db = dm;
        }
      }
      y = std::abs(db) < std::abs(da) ? b : a;
      dy = std::abs(db) < std::abs(da) ? db : da;
    }
    x = y;
    d = dy;
    gx = f.gradient(x);
    const double r = residual_of(d, gx, cap);
    if (r < best.residual) {
      best.point = x;
      best.residual = r;
      best.gradient = gx;
    }
    best.steps = step + 1;
  }
  best.converged = best.residual < opt.tolerance;
  return best;
}

}  // namespace adamesh

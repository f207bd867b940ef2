// Scalar fields and the queries every pipeline stage uses: value, gradient, signed-distance
// estimate and projection onto the iso-surface.
//
// Sign convention: the *inside* of the object is where inside_sign·(f − iso) ≥ 0 (see input.h:
// +1 for volumes, where bright = inside; −1 for implicit inputs, where f < 0 = inside).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "adamesh/vec.h"
#include "adamesh/volume.h"

namespace adamesh {

class ScalarField {
 public:
  virtual ~ScalarField() = default;
  /// f(p) at a world point. Points outside domain() are clamped onto it for sampled fields.
  virtual double value(const Vec3& p) const = 0;
  /// ∇f(p) in world units (per world unit of length).
  virtual Vec3 gradient(const Vec3& p) const = 0;
  /// True when value() and gradient() are exact (analytic shapes, user expressions).
  virtual bool is_analytic() const noexcept { return false; }
  /// The box the field is defined or sampled on (world coordinates).
  virtual Box domain() const = 0;
};

/// Trilinear interpolation of a sampled volume; gradient = trilinear interpolation of central
/// differences at the grid points (one-sided at the border), mapped to world units with the
/// inverse transpose of Grid::index_to_world_matrix(). Computed on the fly (no gradient volume).
/// Keeps a reference to the volume: the volume must outlive the field.
std::unique_ptr<ScalarField> make_volume_field(const Volume& volume);
/// Same, sharing ownership of the volume (the field keeps it alive).
std::shared_ptr<const ScalarField> make_volume_field(std::shared_ptr<const Volume> volume);

/// Built-in analytic shape `name` (see shape_names() in input.h and docs/CONVENTIONS.md): exact
/// value and gradient, negative inside. domain() = `domain` or the shape's default box.
/// Throws Error(invalid_input, "shape:NAME: unknown shape (valid: ...)").
std::shared_ptr<const ScalarField> make_shape_field(const std::string& name,
                                                    const std::optional<Box>& domain = {});

/// User expression in x, y, z (muparser syntax, plus the constant `pi`); gradient by central
/// differences with step 1e-6 · domain.diagonal(). value()/gradient() may be called concurrently.
/// Throws Error(invalid_input, "expr:'EXPR': <parser message>").
std::shared_ptr<const ScalarField> make_expr_field(const std::string& expr, const Box& domain);

/// (f(p) − iso) / |∇f(p)|: signed distance estimate, exact for distance fields. Returns 0 when
/// f(p) == iso and ±infinity-free large values are capped at `cap` when the gradient vanishes.
double signed_distance(const ScalarField& f, double iso, const Vec3& p, double cap = 1e30);

/// `f` with its gradient replaced by central differences of its values, step `h` (world units).
/// For a sampled field this is the derivative of the trilinear interpolant itself, which keeps
/// Newton steps on the sheet of the surface nearest to the point; the field's own gradient
/// (interpolated central differences of the samples) can point elsewhere in thin structures.
/// Keeps a reference to `f`.
std::unique_ptr<ScalarField> make_differenced_field(const ScalarField& f, double h);
/// The same derivative, exact and about 6× cheaper when `f` is a make_volume_field() field (the
/// derivative of its trilinear interpolant, zero along an axis where the point is outside the
/// grid); make_differenced_field(f, h) for any other field.
std::unique_ptr<ScalarField> make_interpolant_gradient_field(const ScalarField& f, double h);

struct ProjectOptions {
  int max_steps = 5;           ///< Newton steps
  double tolerance = 1e-3;     ///< stop when |T_S| < tolerance (world units)
  double max_step = 0.5;       ///< cap on each step's length (world units)
  /// Optional plane constraint: steps are projected into the plane through the start point with
  /// this normal (border vertices stay on their volume face). Zero vector = unconstrained.
  Vec3 plane_normal{};
};

struct ProjectResult {
  Vec3 point;
  double residual = 0;  ///< |signed_distance| at the returned point
  int steps = 0;
  bool converged = false;
  Vec3 gradient;              ///< ∇f at the returned point
  double start_distance = 0;  ///< (f(p) − iso)/|∇f(p)| at the start point (0 when flat there)
};

/// Newton projection p ← p − (f(p) − iso) ∇f/|∇f|² with safeguards: step length capped, flat
/// gradients (|∇f| zero, or a Newton distance beyond 1e6 domain diagonals) stop the iteration, a
/// sign change along a step is resolved by bisection along the step, and the result is the
/// iterate with the smallest residual (never larger than the start point's). With a plane
/// constraint the step is the Newton step along the in-plane part of ∇f.
ProjectResult project_to_iso(const ScalarField& f, double iso, const Vec3& p,
                             const ProjectOptions& opt = {});

}  // namespace adamesh

// User expressions `expr:'...'` evaluated with muparser (https://beltoforion.de/en/muparser/):
// variables x, y, z (world coordinates), muparser's functions and operators, constants pi, _pi, _e.
//
// Thread safety: a mu::Parser is not safe for concurrent Eval() calls, so every thread gets its own
// parser (tbb::enumerable_thread_specific, created on first use in that thread and destroyed with
// the field). Gradient: central differences with step h = 1e-6 · domain diagonal, per axis
// (f(p + h e_a) − f(p − h e_a)) / 2h: error O(h²·f''') + O(ε·|f|/h), i.e. ~1e-10 relative for
// smooth expressions of unit scale.
#include <muParser.h>
#include <tbb/enumerable_thread_specific.h>

#include <memory>
#include <numbers>

#include "adamesh/error.h"
#include "adamesh/field.h"

namespace adamesh {

namespace {

struct Evaluator {
  double x = 0, y = 0, z = 0;
  mu::Parser parser;

  explicit Evaluator(const std::string& expr) {
    parser.DefineVar("x", &x);
    parser.DefineVar("y", &y);
    parser.DefineVar("z", &z);
    parser.DefineConst("pi", std::numbers::pi);
    parser.SetExpr(expr);
  }
  double operator()(const Vec3& p) {
    x = p.x;
    y = p.y;
    z = p.z;
    return parser.Eval();
  }
};

std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

class ExprField final : public ScalarField {
 public:
  ExprField(const std::string& expr, const Box& domain)
      : expr_(expr),
        domain_(domain),
        h_(1e-6 * (domain.diagonal() > 0 ? domain.diagonal() : 1.0)),
        evaluators_([this] { return std::make_unique<Evaluator>(expr_); }) {
    // Parse now (muparser parses lazily on the first Eval) so errors surface at construction.
    try {
      auto& e = evaluators_.local();
      (*e)(0.5 * (domain.lo + domain.hi));
    } catch (const mu::Parser::exception_type& err) {
      fail_input("expr:'" + expr_ + "'", one_line(err.GetMsg()));
    }
  }

  double value(const Vec3& p) const override { return (*evaluators_.local())(p); }

  Vec3 gradient(const Vec3& p) const override {
    Evaluator& e = *evaluators_.local();
    Vec3 g;
    for (int a = 0; a < 3; ++a) {
      Vec3 lo = p, hi = p;
      lo[a] -= h_;
      hi[a] += h_;
      g[a] = (e(hi) - e(lo)) / (hi[a] - lo[a]);
    }
    return g;
  }

  bool is_analytic() const noexcept override { return true; }
  Box domain() const override { return domain_; }

 private:
  std::string expr_;
  Box domain_;
  double h_;
  mutable tbb::enumerable_thread_specific<std::unique_ptr<Evaluator>> evaluators_;
};

}  // namespace

std::shared_ptr<const ScalarField> make_expr_field(const std::string& expr, const Box& domain) {
  if (expr.find_first_not_of(" \t") == std::string::npos) fail_input("expr:''", "empty expression");
  return std::make_shared<ExprField>(expr, domain);
}

}  // namespace adamesh

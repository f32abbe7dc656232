#pragma once
// User-written analytic size functions (`--size-expr`, like Gmsh's MathEval
// field): an arithmetic expression of x, y, z, parsed once into a postfix
// program that is then evaluated at every size query.
//
// Grammar (whitespace is ignored, names are case-sensitive):
//   expr    := term (('+' | '-') term)*
//   term    := unary (('*' | '/') unary)*
//   unary   := ('+' | '-') unary | power
//   power   := primary ['^' unary]          right-associative: 2^3^2 = 2^9,
//                                           and -x^2 = -(x^2) as in maths
//   primary := number | 'x' | 'y' | 'z' | 'pi' | '(' expr ')'
//            | function '(' [expr (',' expr)*] ')'
//   number  := (digits ['.' [digits]] | '.' digits) [('e' | 'E') ['+' | '-'] digits]
// Functions: sqrt exp log (natural) sin cos tan abs take 1 argument; atan2
// pow hypot take 2; min max take 2 or more.
//
// Evaluation follows IEEE arithmetic without checks (log(-1) is NaN, 1/0 is
// inf); min and max propagate NaN. Rejecting non-finite or non-positive sizes
// is the size field's job (AnalyticSizeField).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "curvemesh/core/types.hpp"
#include "curvemesh/size/size_field.hpp"

namespace cm::size {

/// A parsed arithmetic expression of x, y, z.
class Expression {
 public:
  /// Longest evaluation stack an expression may need; parse() rejects
  /// deeper ones (no realistic size function comes close).
  static constexpr std::size_t kMaxStack = 64;

  /// Parses `text`. Throws cm::InputError with file "--size-expr", line -1,
  /// byte_offset the 0-based column of the problem, and a reason that starts
  /// with the 1-based column, e.g. "column 7: expected ')', got end of input",
  /// "column 1: unknown function 'sine'", "column 3: unknown variable 'w'".
  /// Rejects empty input, trailing text, wrong argument counts, unbalanced
  /// parentheses, numbers that do not fit a double and over-deep nesting.
  static Expression parse(std::string_view text);

  /// The value at p. Thread-safe; does not allocate.
  double operator()(const Vec3& p) const;

  /// The text it was parsed from.
  const std::string& text() const { return text_; }

 private:
  // Grouped by arity; the parser relies on this order.
  // clang-format off
  enum class Op : std::uint8_t {
    Const, X, Y, Z,                                   // push a value
    Neg, Square, Sqrt, Exp, Log, Sin, Cos, Tan, Abs,  // replace the top
    Add, Sub, Mul, Div, Pow, Atan2, Hypot, Min, Max,  // pop b, replace a by (a op b)
  };
  // clang-format on
  struct Instr {
    Op op;
    double value;  ///< Const only
  };
  class Parser;

  Expression(std::string text, std::vector<Instr> code)
      : text_(std::move(text)), code_(std::move(code)) {}
  /// Runs a postfix program; the parser uses it to fold constants, so folding
  /// cannot disagree with evaluation.
  static double run(const Instr* code, std::size_t size, const Vec3& p);

  std::string text_;
  std::vector<Instr> code_;  ///< postfix; leaves exactly one value, needs <= kMaxStack slots
};

/// An AnalyticSizeField evaluating Expression::parse(text); throws as parse()
/// does. Its size() throws std::domain_error where the value is not finite
/// and > 0.
std::shared_ptr<const SizeField> make_expression_field(std::string_view text);

}  // namespace cm::size

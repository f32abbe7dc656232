// Analytic size expressions (--size-expr): grammar, functions, errors, threads.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "curvemesh/core/error.hpp"
#include "curvemesh/size/expression.hpp"

using namespace cm;
using namespace cm::size;

namespace {

double eval(std::string_view text, const Vec3& p = Vec3::Zero()) {
  return Expression::parse(text)(p);
}

std::vector<Vec3> random_points(std::size_t n, double lo, double hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<Vec3> points(n);
  for (auto& p : points) p = Vec3(u(rng), u(rng), u(rng));
  return points;
}

}  // namespace

TEST(Expression, PrecedenceAndAssociativity) {
  EXPECT_EQ(eval("2^3^2"), 512);
  EXPECT_EQ(eval("-2^2"), -4);
  EXPECT_EQ(eval("1-2-3"), -4);
  EXPECT_EQ(eval("8/4/2"), 1);
  EXPECT_EQ(eval("2+3*4"), 14);
  EXPECT_EQ(eval("(2+3)*4"), 20);
  EXPECT_EQ(eval("2*3^2"), 18);
  EXPECT_EQ(eval("2^-1"), 0.5);
  EXPECT_EQ(eval("-(2)^2"), -4);
  EXPECT_EQ(eval("(-2)^2"), 4);
  EXPECT_EQ(eval("--3"), 3);
  EXPECT_EQ(eval("+3"), 3);
  EXPECT_EQ(eval("1--2"), 3);
  EXPECT_EQ(eval("2*-3"), -6);
  EXPECT_EQ(eval("12/3*2"), 8) << "* and / associate to the left together";
  EXPECT_EQ(eval("1-2+3"), 2) << "+ and - associate to the left together";
  // The same with variables, so the evaluator (not only constant folding) is checked.
  EXPECT_EQ(eval("x^y^z", {2, 3, 2}), 512);
  EXPECT_EQ(eval("-x^y", {2, 2, 0}), -4);
  EXPECT_EQ(eval("x-y-z", {1, 2, 3}), -4);
  EXPECT_EQ(eval("x/y/z", {8, 4, 2}), 1);
  EXPECT_EQ(eval("x+y*z", {2, 3, 4}), 14);
  EXPECT_EQ(eval("-x^2", {3, 0, 0}), -9);
  EXPECT_EQ(eval("x^-y", {2, 1, 0}), 0.5);
}

TEST(Expression, FunctionsMatchCmath) {
  struct Case {
    const char* text;
    std::function<double(double, double, double)> expect;
  };
  const std::vector<Case> cases = {
      {"sqrt(x)", [](double x, double, double) { return std::sqrt(x); }},
      {"exp(x)", [](double x, double, double) { return std::exp(x); }},
      {"log(x)", [](double x, double, double) { return std::log(x); }},
      {"sin(x)", [](double x, double, double) { return std::sin(x); }},
      {"cos(y)", [](double, double y, double) { return std::cos(y); }},
      {"tan(z)", [](double, double, double z) { return std::tan(z); }},
      {"abs(x)", [](double x, double, double) { return std::abs(x); }},
      {"atan2(y, x)", [](double x, double y, double) { return std::atan2(y, x); }},
      {"pow(x, y)", [](double x, double y, double) { return std::pow(x, y); }},
      {"x^y", [](double x, double y, double) { return std::pow(x, y); }},
      {"x^2", [](double x, double, double) { return std::pow(x, 2); }},
      {"(x+y)^2^0.5", [](double x, double y, double) { return std::pow(x + y, std::pow(2, 0.5)); }},
      {"y^(1+1)", [](double, double y, double) { return std::pow(y, 2); }},
      {"hypot(x, z)", [](double x, double, double z) { return std::hypot(x, z); }},
      {"min(x, y)", [](double x, double y, double) { return std::min(x, y); }},
      {"max(x, y)", [](double x, double y, double) { return std::max(x, y); }},
      {"min(x, y, z)",
       [](double x, double y, double z) {
         return std::min({x, y, z});
       }},
      {"max(z, y, x, 0.5)",
       [](double x, double y, double z) {
         return std::max({x, y, z, 0.5});
       }},
      {"sqrt(abs(x*y)) + log(1 + z^2)",
       [](double x, double y, double z) {
         return std::sqrt(std::abs(x * y)) + std::log(1 + std::pow(z, 2.0));
       }},
  };
  // Negative arguments too: sqrt, log and pow must give NaN exactly where <cmath> does.
  const auto points = random_points(200, -3, 3, 7);
  for (const auto& c : cases) {
    const auto e = Expression::parse(c.text);
    EXPECT_EQ(e.text(), c.text);
    for (const auto& p : points) {
      const double want = c.expect(p.x(), p.y(), p.z());
      const double got = e(p);
      if (std::isnan(want))
        EXPECT_TRUE(std::isnan(got)) << c.text << " at " << p.transpose();
      else
        EXPECT_DOUBLE_EQ(got, want) << c.text << " at " << p.transpose();
    }
  }
}

TEST(Expression, MinAndMaxPropagateNan) {
  // std::min/max would drop the NaN and hand the mesher a valid-looking size.
  EXPECT_TRUE(std::isnan(eval("min(sqrt(x), 1)", {-1, 0, 0})));
  EXPECT_TRUE(std::isnan(eval("min(1, sqrt(x))", {-1, 0, 0})));
  EXPECT_TRUE(std::isnan(eval("max(sqrt(x), 1)", {-1, 0, 0})));
  EXPECT_TRUE(std::isnan(eval("max(1, 2, sqrt(x))", {-1, 0, 0})));
  EXPECT_TRUE(std::isnan(eval("min(1, 2, log(-1))")));
}

TEST(Expression, VariablesAndPi) {
  const Vec3 p(1.25, -2.5, 4.0);
  EXPECT_EQ(eval("x", p), 1.25);
  EXPECT_EQ(eval("y", p), -2.5);
  EXPECT_EQ(eval("z", p), 4.0);
  EXPECT_EQ(eval("pi"), std::numbers::pi);
  EXPECT_DOUBLE_EQ(eval("2*pi*x", p), 2 * std::numbers::pi * 1.25);
  EXPECT_DOUBLE_EQ(eval("sin(pi/2)"), 1.0);
  EXPECT_DOUBLE_EQ(eval("x*y*z + x/z", p), 1.25 * -2.5 * 4.0 + 1.25 / 4.0);
}

TEST(Expression, Numbers) {
  EXPECT_EQ(eval("123"), 123);
  EXPECT_EQ(eval("1.5"), 1.5);
  EXPECT_EQ(eval(".5"), 0.5);
  EXPECT_EQ(eval("5."), 5);
  EXPECT_EQ(eval("007"), 7);
  EXPECT_EQ(eval("1e-3"), 1e-3);
  EXPECT_EQ(eval("2.5E+2"), 250);
  EXPECT_EQ(eval("1E3"), 1000);
  EXPECT_EQ(eval(".5e1"), 5);
  EXPECT_EQ(eval("1.7976931348623157e308"), 1.7976931348623157e308);
  EXPECT_EQ(eval("2e-1*x", {5, 0, 0}), 1);
}

TEST(Expression, WhitespaceIsIgnored) {
  const Vec3 p(0.3, 0.7, -1.1);
  const double compact = eval("x+2*(y-z)^2/sqrt(x)+max(x,y)", p);
  EXPECT_EQ(eval(" \t x +\n2 * ( y - z ) ^ 2 / sqrt ( x )\r\n + max ( x , y ) \t", p), compact);
}

TEST(Expression, ErrorsNameTheColumn) {
  struct Case {
    std::string text;
    std::int64_t column;  // 0-based
    const char* message;
  };
  const std::vector<Case> cases = {
      {"", 0, "empty expression"},
      {"  ", 2, "empty expression"},
      {"(x+1", 4, "expected ')', got end of input"},
      {"((x)", 4, "expected ')', got end of input"},
      {"x+1)", 3, "unmatched ')'"},
      {"2 3", 2, "expected an operator or end of input, got number '3'"},
      {"2x", 1, "expected an operator or end of input, got 'x'"},
      {"x # y", 2, "expected an operator or end of input, got '#'"},
      {"sine(x)", 0, "unknown function 'sine'"},
      {"x + w", 4, "unknown variable 'w'"},
      {"X", 0, "unknown variable 'X'"},
      {"x(2)", 0, "'x' is not a function"},
      {"sqrt x", 5, "expected '(' after function 'sqrt', got 'x'"},
      {"1 + sqrt(x, y)", 4, "sqrt takes 1 argument, got 2"},
      {"sqrt()", 0, "sqrt takes 1 argument, got 0"},
      {"atan2(x)", 0, "atan2 takes 2 arguments, got 1"},
      {"hypot(x, y, z)", 0, "hypot takes 2 arguments, got 3"},
      {"min(x)", 0, "min takes at least 2 arguments, got 1"},
      {"max(x, y", 8, "expected ',' or ')', got end of input"},
      {"max(", 4, "expected a number, variable, function or '(', got end of input"},
      {"x*", 2, "expected a number, variable, function or '(', got end of input"},
      {"()", 1, "expected a number, variable, function or '(', got ')'"},
      {"x*/y", 2, "expected a number, variable, function or '(', got '/'"},
      {"1,2", 1, "expected an operator or end of input, got ','"},
      {"1e999", 0, "number '1e999' is out of range"},
      {"x + 1e-400", 4, "number '1e-400' is out of range"},
      {"1e+", 3, "expected a digit in the exponent of '1e+', got end of input"},
      {"2ex", 2, "expected a digit in the exponent of '2e', got 'x'"},
      {"x . 2", 2, "expected an operator or end of input, got '.'"},
      {"x + \xC3\xA9", 4, "expected a number, variable, function or '(', got byte 0xC3"},
  };
  for (const auto& c : cases) {
    try {
      Expression::parse(c.text);
      ADD_FAILURE() << "'" << c.text << "' parsed";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "--size-expr");
      EXPECT_EQ(e.line(), -1);
      EXPECT_EQ(e.byte_offset(), c.column) << c.text << ": " << e.what();
      EXPECT_EQ(e.reason(), fmt::format("column {}: {}", c.column + 1, c.message)) << c.text;
    }
  }
  try {
    Expression::parse("sin(x) + (y");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "--size-expr: byte 11: column 12: expected ')', got end of input");
  }
}

TEST(Expression, DeepNestingIsBoundedNotACrash) {
  // Right-nested sums keep one operand per level on the evaluation stack.
  const auto nested = [](int levels) {
    std::string s;
    for (int i = 0; i < levels; ++i) s += "x+(";
    s += "x";
    s += std::string(static_cast<std::size_t>(levels), ')');
    return s;
  };
  const int fits = static_cast<int>(Expression::kMaxStack) - 1;
  EXPECT_EQ(eval(nested(fits), {1, 0, 0}), fits + 1);
  EXPECT_THROW(Expression::parse(nested(fits + 1)), InputError);
  // Parenthesis and sign nesting needs no stack slots but parser recursion.
  EXPECT_THROW(Expression::parse(std::string(100000, '(') + "1" + std::string(100000, ')')),
               InputError);
  EXPECT_THROW(Expression::parse(std::string(100000, '-') + "1"), InputError);
  EXPECT_EQ(eval(std::string(50, '(') + "x" + std::string(50, ')'), {2, 0, 0}), 2);
  // Variadic min keeps two slots however many arguments it has.
  std::string many = "min(x";
  for (int i = 0; i < 1000; ++i) many += fmt::format(", x+{}", i);
  EXPECT_EQ(eval(many + ")", {-5, 0, 0}), -5);
}

TEST(Expression, ConcurrentEvaluationMatchesSerial) {
  const auto e = Expression::parse(
      "0.05 + 0.1*sqrt(x^2+y^2) * (1 + 0.5*sin(3*z)) + min(abs(x), hypot(y, z), 2)");
  const auto points = random_points(200000, -2, 2, 11);
  std::vector<double> serial(points.size()), parallel(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) serial[i] = e(points[i]);
  tbb::parallel_for(std::size_t{0}, points.size(),
                    [&](std::size_t i) { parallel[i] = e(points[i]); });
  EXPECT_EQ(serial, parallel);
}

TEST(Expression, SizeFieldEvaluatesTheExpression) {
  const auto field = make_expression_field("0.05 + 0.1*sqrt(x^2+y^2) * (1 + 0.5*sin(3*z))");
  const auto e = Expression::parse("0.05 + 0.1*sqrt(x^2+y^2) * (1 + 0.5*sin(3*z))");
  for (const auto& p : random_points(100, -1, 1, 3)) EXPECT_EQ(field->size(p), e(p));
  EXPECT_FALSE(field->anisotropic());

  const auto bad = make_expression_field("x");
  EXPECT_EQ(bad->size({0.5, 0, 0}), 0.5);
  EXPECT_THROW(bad->size({-0.5, 0, 0}), std::domain_error);
  EXPECT_THROW(bad->size({0, 0, 0}), std::domain_error);
  EXPECT_THROW(make_expression_field("sqrt(x-1)")->size({0, 0, 0}), std::domain_error);
  EXPECT_THROW(make_expression_field("1/x")->size({0, 0, 0}), std::domain_error);
  EXPECT_THROW(make_expression_field("0.1 +"), InputError);
}

#include "curvemesh/size/expression.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <numbers>
#include <system_error>

#include "curvemesh/core/error.hpp"

namespace cm::size {

namespace {

// Parentheses, unary signs, exponents and arguments each nest one level; the
// limit keeps hostile input ("((((...") from overflowing the parser's stack.
constexpr int kMaxNesting = 100;

[[noreturn]] void fail(std::size_t offset, const std::string& message) {
  throw InputError("--size-expr", -1, static_cast<std::int64_t>(offset),
                   fmt::format("column {}: {}", offset + 1, message));
}

bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_name_start(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
bool is_name_char(char c) { return is_name_start(c) || is_digit(c); }
bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

// std::min/std::max return the other argument when one is NaN, which would
// turn e.g. min(sqrt(x), 1) at x < 0 into a valid-looking size.
double min_nan(double a, double b) { return (a < b || std::isnan(a)) ? a : b; }
double max_nan(double a, double b) { return (a > b || std::isnan(a)) ? a : b; }

struct Token {
  enum class Kind { Number, Name, Symbol, End };
  Kind kind = Kind::End;
  std::size_t pos = 0;
  std::string_view text;
  double value = 0;  ///< Number only

  bool is(char c) const { return kind == Kind::Symbol && text.front() == c; }
};

/// The byte at text[i] (or the end) as an error message shows it.
std::string describe_at(std::string_view text, std::size_t i) {
  if (i >= text.size()) return "end of input";
  const auto c = static_cast<unsigned char>(text[i]);
  if (c >= 0x20 && c < 0x7f) return fmt::format("'{}'", text[i]);
  return fmt::format("byte 0x{:02X}", c);
}

std::string describe(const Token& t) {
  switch (t.kind) {
    case Token::Kind::Number:
      return fmt::format("number '{}'", t.text);
    case Token::Kind::Name:
      return fmt::format("'{}'", t.text);
    case Token::Kind::Symbol:
      return describe_at(t.text, 0);
    case Token::Kind::End:
      break;
  }
  return "end of input";
}

}  // namespace

class Expression::Parser {
 public:
  explicit Parser(std::string_view text) : text_(text) { advance(); }

  std::vector<Instr> parse() {
    if (tok_.kind == Token::Kind::End) fail(tok_.pos, "empty expression");
    parse_sum();
    if (tok_.is(')')) fail(tok_.pos, "unmatched ')'");
    if (tok_.kind != Token::Kind::End)
      fail(tok_.pos, fmt::format("expected an operator or end of input, got {}", describe(tok_)));
    CM_ASSERT_OP(depth_, ==, std::size_t{1});
    return std::move(code_);
  }

 private:
  struct Function {
    std::string_view name;
    Op op;
    int min_args, max_args;
  };
  static constexpr int kVariadic = -1;

  static const Function* find_function(std::string_view name) {
    static constexpr Function kFunctions[] = {
        {"sqrt", Op::Sqrt, 1, 1},   {"exp", Op::Exp, 1, 1},         {"log", Op::Log, 1, 1},
        {"sin", Op::Sin, 1, 1},     {"cos", Op::Cos, 1, 1},         {"tan", Op::Tan, 1, 1},
        {"abs", Op::Abs, 1, 1},     {"atan2", Op::Atan2, 2, 2},     {"pow", Op::Pow, 2, 2},
        {"hypot", Op::Hypot, 2, 2}, {"min", Op::Min, 2, kVariadic}, {"max", Op::Max, 2, kVariadic},
    };
    for (const Function& f : kFunctions)
      if (f.name == name) return &f;
    return nullptr;
  }

  static int arity(Op op) {
    if (op <= Op::Z) return 0;
    if (op <= Op::Abs) return 1;
    return 2;
  }

  // --- lexer -------------------------------------------------------------

  void advance() {
    std::size_t i = cursor_;
    while (i < text_.size() && is_space(text_[i])) ++i;
    tok_ = Token{};
    tok_.pos = i;
    if (i == text_.size()) {
      cursor_ = i;
      return;
    }
    const char c = text_[i];
    if (is_digit(c) || (c == '.' && i + 1 < text_.size() && is_digit(text_[i + 1])))
      return lex_number(i);
    std::size_t end = i + 1;
    if (is_name_start(c)) {
      while (end < text_.size() && is_name_char(text_[end])) ++end;
      tok_.kind = Token::Kind::Name;
    } else {
      // Operators, and any other byte as a token of its own for the error message.
      tok_.kind = Token::Kind::Symbol;
    }
    tok_.text = text_.substr(i, end - i);
    cursor_ = end;
  }

  void lex_number(std::size_t start) {
    std::size_t i = start;
    const auto digits = [&] {
      while (i < text_.size() && is_digit(text_[i])) ++i;
    };
    digits();
    if (i < text_.size() && text_[i] == '.') {
      ++i;
      digits();
    }
    if (i < text_.size() && (text_[i] == 'e' || text_[i] == 'E')) {
      ++i;
      if (i < text_.size() && (text_[i] == '+' || text_[i] == '-')) ++i;
      if (i == text_.size() || !is_digit(text_[i]))
        fail(i, fmt::format("expected a digit in the exponent of '{}', got {}",
                            text_.substr(start, i - start), describe_at(text_, i)));
      digits();
    }
    tok_.kind = Token::Kind::Number;
    tok_.text = text_.substr(start, i - start);
    cursor_ = i;
    const auto [ptr, ec] =
        std::from_chars(tok_.text.data(), tok_.text.data() + tok_.text.size(), tok_.value);
    if (ec == std::errc::result_out_of_range)
      fail(start, fmt::format("number '{}' is out of range", tok_.text));
    // The scan above only accepts what from_chars parses in full.
    CM_ASSERT(ec == std::errc{} && ptr == tok_.text.data() + tok_.text.size());
  }

  // --- grammar (expression.hpp) -------------------------------------------

  void parse_sum() {
    parse_product();
    while (tok_.is('+') || tok_.is('-')) {
      const Op op = tok_.is('+') ? Op::Add : Op::Sub;
      advance();
      parse_product();
      emit(op);
    }
  }

  void parse_product() {
    parse_unary();
    while (tok_.is('*') || tok_.is('/')) {
      const Op op = tok_.is('*') ? Op::Mul : Op::Div;
      advance();
      parse_unary();
      emit(op);
    }
  }

  void parse_unary() {
    if (++nesting_ > kMaxNesting)
      fail(tok_.pos, fmt::format("expression nested more than {} levels deep", kMaxNesting));
    if (tok_.is('+')) {
      advance();
      parse_unary();
    } else if (tok_.is('-')) {
      advance();
      parse_unary();
      emit(Op::Neg);
    } else {
      parse_power();
    }
    --nesting_;
  }

  void parse_power() {
    parse_primary();
    if (tok_.is('^')) {
      advance();
      parse_unary();  // right-associative, and 2^-1 is allowed
      emit(Op::Pow);
    }
  }

  void parse_primary() {
    const Token t = tok_;
    if (t.kind == Token::Kind::Number) {
      push(Op::Const, t.value, t.pos);
      advance();
    } else if (t.is('(')) {
      advance();
      parse_sum();
      expect(')', "')'");
    } else if (t.kind == Token::Kind::Name) {
      advance();
      if (tok_.is('(')) return parse_call(t);
      if (t.text == "x") return push(Op::X, 0, t.pos);
      if (t.text == "y") return push(Op::Y, 0, t.pos);
      if (t.text == "z") return push(Op::Z, 0, t.pos);
      if (t.text == "pi") return push(Op::Const, std::numbers::pi, t.pos);
      if (find_function(t.text))
        fail(tok_.pos,
             fmt::format("expected '(' after function '{}', got {}", t.text, describe(tok_)));
      fail(t.pos, fmt::format("unknown variable '{}'", t.text));
    } else {
      fail(t.pos, fmt::format("expected a number, variable, function or '(', got {}", describe(t)));
    }
  }

  void parse_call(const Token& name) {
    const Function* f = find_function(name.text);
    if (!f) {
      if (name.text == "x" || name.text == "y" || name.text == "z" || name.text == "pi")
        fail(name.pos, fmt::format("'{}' is not a function", name.text));
      fail(name.pos, fmt::format("unknown function '{}'", name.text));
    }
    advance();  // '('
    int count = 0;
    if (!tok_.is(')')) {
      while (true) {
        parse_sum();
        // Fold variadic arguments as they come so min(a, b, c, ...) needs
        // two stack slots, not one per argument.
        if (++count >= 2 && f->max_args == kVariadic) emit(f->op);
        if (!tok_.is(',')) break;
        advance();
      }
    }
    expect(')', "',' or ')'");
    if (count < f->min_args || (f->max_args != kVariadic && count > f->max_args)) {
      const std::string need = f->max_args == kVariadic ? fmt::format("at least {}", f->min_args)
                                                        : fmt::format("{}", f->min_args);
      fail(name.pos, fmt::format("{} takes {} argument{}, got {}", f->name, need,
                                 f->min_args == 1 ? "" : "s", count));
    }
    if (f->max_args != kVariadic) emit(f->op);
  }

  void expect(char c, std::string_view what) {
    if (!tok_.is(c)) fail(tok_.pos, fmt::format("expected {}, got {}", what, describe(tok_)));
    advance();
  }

  // --- code generation ----------------------------------------------------

  void push(Op op, double value, std::size_t pos) {
    if (++depth_ > kMaxStack)
      fail(pos, fmt::format("expression needs more than {} evaluation stack slots", kMaxStack));
    code_.push_back({op, value});
  }

  /// Appends an operation; when all its operands are constants it is
  /// evaluated now (3*z, 2*pi, -1) to shorten the program run per query.
  void emit(Op op) {
    // a^2 is the common case (radial distances, x^2+y^2); std::pow took half
    // the evaluation time of such size functions, a multiplication is free.
    if (op == Op::Pow && code_.back().op == Op::Const && code_.back().value == 2) {
      code_.pop_back();
      --depth_;
      op = Op::Square;
    }
    const int k = arity(op);
    depth_ -= static_cast<std::size_t>(k - 1);
    code_.push_back({op, 0});
    const std::size_t first = code_.size() - 1 - static_cast<std::size_t>(k);
    for (std::size_t i = first; i + 1 < code_.size(); ++i)
      if (code_[i].op != Op::Const) return;
    const double value = run(&code_[first], code_.size() - first, Vec3::Zero());
    code_.resize(first);
    code_.push_back({Op::Const, value});
  }

  std::string_view text_;
  std::size_t cursor_ = 0;  ///< where the token after tok_ starts
  Token tok_;
  std::vector<Instr> code_;
  std::size_t depth_ = 0;  ///< stack depth after the code so far
  int nesting_ = 0;
};

Expression Expression::parse(std::string_view text) {
  return Expression(std::string(text), Parser(text).parse());
}

double Expression::run(const Instr* code, std::size_t size, const Vec3& p) {
  double s[kMaxStack];  // the parser bounds the depth
  std::size_t n = 0;
  for (const Instr* in = code; in != code + size; ++in) {
    switch (in->op) {
      case Op::Const:
        s[n++] = in->value;
        break;
      case Op::X:
        s[n++] = p.x();
        break;
      case Op::Y:
        s[n++] = p.y();
        break;
      case Op::Z:
        s[n++] = p.z();
        break;
      case Op::Neg:
        s[n - 1] = -s[n - 1];
        break;
      case Op::Square:
        s[n - 1] *= s[n - 1];
        break;
      case Op::Sqrt:
        s[n - 1] = std::sqrt(s[n - 1]);
        break;
      case Op::Exp:
        s[n - 1] = std::exp(s[n - 1]);
        break;
      case Op::Log:
        s[n - 1] = std::log(s[n - 1]);
        break;
      case Op::Sin:
        s[n - 1] = std::sin(s[n - 1]);
        break;
      case Op::Cos:
        s[n - 1] = std::cos(s[n - 1]);
        break;
      case Op::Tan:
        s[n - 1] = std::tan(s[n - 1]);
        break;
      case Op::Abs:
        s[n - 1] = std::abs(s[n - 1]);
        break;
      case Op::Add:
        --n;
        s[n - 1] += s[n];
        break;
      case Op::Sub:
        --n;
        s[n - 1] -= s[n];
        break;
      case Op::Mul:
        --n;
        s[n - 1] *= s[n];
        break;
      case Op::Div:
        --n;
        s[n - 1] /= s[n];
        break;
      case Op::Pow:
        --n;
        s[n - 1] = std::pow(s[n - 1], s[n]);
        break;
      case Op::Atan2:
        --n;
        s[n - 1] = std::atan2(s[n - 1], s[n]);
        break;
      case Op::Hypot:
        --n;
        s[n - 1] = std::hypot(s[n - 1], s[n]);
        break;
      case Op::Min:
        --n;
        s[n - 1] = min_nan(s[n - 1], s[n]);
        break;
      case Op::Max:
        --n;
        s[n - 1] = max_nan(s[n - 1], s[n]);
        break;
    }
  }
  return s[0];
}

double Expression::operator()(const Vec3& p) const { return run(code_.data(), code_.size(), p); }

std::shared_ptr<const SizeField> make_expression_field(std::string_view text) {
  return std::make_shared<AnalyticSizeField>(
      [e = Expression::parse(text)](const Vec3& p) { return e(p); });
}

}  // namespace cm::size

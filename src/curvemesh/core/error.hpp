#pragma once
// Typed errors thrown by library code. The CLI maps each type to one exit code
// (cli/exit_codes.hpp); operator refusals are values, never exceptions.
#include <cstdint>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace cm {

/// Unreadable or malformed input. `line` is 1-based for text formats; for
/// binary formats `byte_offset` is set instead (the other one is -1).
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::int64_t line, std::int64_t byte_offset, std::string reason);
  const std::string& file() const { return file_; }
  std::int64_t line() const { return line_; }
  std::int64_t byte_offset() const { return byte_offset_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string file_;
  std::int64_t line_;
  std::int64_t byte_offset_;
  std::string reason_;
};

/// A geometric model that cannot be used (broken B-rep, no solid, ...).
class GeometryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A broken internal invariant: a bug in curvemesh, never the user's fault.
class InternalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

[[noreturn]] void fail_assertion(const char* expr, const char* file, int line, const std::string& detail);

}  // namespace cm

/// Always-on assertion; throws InternalError with the failing expression.
#define CM_ASSERT(expr)                                              \
  do {                                                               \
    if (!(expr)) ::cm::fail_assertion(#expr, __FILE__, __LINE__, ""); \
  } while (0)

/// Comparison assertion that prints both operands.
#define CM_ASSERT_OP(a, op, b)                                                          \
  do {                                                                                  \
    const auto& cm_a_ = (a);                                                            \
    const auto& cm_b_ = (b);                                                            \
    if (!(cm_a_ op cm_b_))                                                              \
      ::cm::fail_assertion(#a " " #op " " #b, __FILE__, __LINE__,                       \
                           ::fmt::format("{} vs {}", cm_a_, cm_b_));                    \
  } while (0)

#ifndef NDEBUG
#define CM_DEBUG_ASSERT(expr) CM_ASSERT(expr)
#else
#define CM_DEBUG_ASSERT(expr) \
  do {                        \
  } while (0)
#endif

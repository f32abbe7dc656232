#include "curvemesh/core/error.hpp"

namespace cm {

namespace {
std::string format_input_error(const std::string& file, std::int64_t line, std::int64_t offset,
                               const std::string& reason) {
  if (line >= 0) return fmt::format("{}:{}: {}", file, line, reason);
  if (offset >= 0) return fmt::format("{}: byte {}: {}", file, offset, reason);
  return fmt::format("{}: {}", file, reason);
}
}  // namespace

InputError::InputError(std::string file, std::int64_t line, std::int64_t byte_offset,
                       std::string reason)
    : std::runtime_error(format_input_error(file, line, byte_offset, reason)),
      file_(std::move(file)),
      line_(line),
      byte_offset_(byte_offset),
      reason_(std::move(reason)) {}

void fail_assertion(const char* expr, const char* file, int line, const std::string& detail) {
  throw InternalError(fmt::format("internal error: assertion '{}' failed at {}:{}{}{}", expr, file,
                                  line, detail.empty() ? "" : ": ", detail));
}

}  // namespace cm

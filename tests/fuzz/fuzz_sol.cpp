// libFuzzer target for the MMG solution reader (.sol and .solb). As for
// fuzz_medit, each input is read as given and behind a binary header word.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "curvemesh/core/error.hpp"
#include "curvemesh/io/formats.hpp"

namespace {

// What the reader accepts must be usable: whole records of finite values.
void check_sol(const cm::io::SolField& sol) {
  const std::size_t size = sol.type == cm::io::SolField::Type::kScalar ? 1 : 6;
  bool ok = sol.values.size() % size == 0;
  for (double v : sol.values) ok = ok && std::isfinite(v);
  if (!ok) __builtin_trap();
}

void read(std::string_view bytes) {
  try {
    check_sol(cm::io::read_sol(bytes, "fuzz.sol"));
  } catch (const cm::InputError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  read(bytes);
  read(std::string("\x01\x00\x00\x00", 4).append(bytes));
  return 0;
}

// libFuzzer target for the Medit mesh reader (.mesh and .meshb). The reader
// chooses text or binary from the first word; each input is also read with a
// binary header word in front, so that the binary parser sees every input.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "curvemesh/core/error.hpp"
#include "curvemesh/io/formats.hpp"

namespace {

// What the reader accepts must be usable: indices in range, finite coordinates.
void check_mesh(const cm::mesh::TetMesh& m) {
  const std::size_t nv = m.num_verts();
  bool ok = m.tet_region.size() == m.num_tets() && m.vert_class.size() == nv;
  for (const auto& x : m.coords)
    ok = ok && std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]);
  for (const auto& t : m.tet2verts)
    for (auto v : t) ok = ok && v < nv;
  for (const auto& t : m.tris)
    for (auto v : t.verts) ok = ok && v < nv;
  for (const auto& e : m.edges)
    for (auto v : e.verts) ok = ok && v < nv;
  if (!ok) __builtin_trap();
}

void read(std::string_view bytes) {
  try {
    check_mesh(cm::io::read_medit(bytes, "fuzz.mesh"));
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

// libFuzzer target for the Gmsh MSH reader. Malformed input must end in
// cm::InputError; any other exception, crash, leak or sanitizer report
// escapes and is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "curvemesh/core/error.hpp"
#include "curvemesh/io/formats.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    const cm::mesh::TetMesh m = cm::io::read_msh(bytes, "fuzz.msh");
    // Touch the result so the reader's output is used.
    volatile std::size_t sink = m.num_verts() + m.num_tets() + m.tris.size() + m.edges.size();
    static_cast<void>(sink);
  } catch (const cm::InputError&) {
  }
  return 0;
}

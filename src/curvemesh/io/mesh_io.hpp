#pragma once
// Reading and writing meshes by file extension.
//   .msh   Gmsh MSH 4.1 (write; ASCII unless binary) / MSH 2.2, 4.1 (read)
//   .mesh  Medit ASCII      .meshb  Medit binary
//   .vtu   VTK XML (write only)
#include <string>

#include "curvemesh/io/formats.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::io {

enum class FileFormat { kMsh, kMedit, kMeditBinary, kVtu, kSol, kSolBinary };

/// Format from the extension; throws InputError (reason names the supported
/// extensions) for anything else.
FileFormat format_from_path(const std::string& path);

/// Reads a mesh, builds adjacency and derives the classification the file
/// does not carry (mesh::derive_classification). Throws InputError.
mesh::TetMesh read_mesh(const std::string& path);

struct WriteOptions {
  bool binary = false;                ///< MSH 4.1 binary
  std::vector<CellField> cell_fields; ///< .vtu only
};
/// Writes through a temporary file renamed on success.
void write_mesh(const mesh::TetMesh& m, const std::string& path, const WriteOptions& options = {});

}  // namespace cm::io

#include "curvemesh/io/mesh_io.hpp"

#include <algorithm>
#include <cctype>

#include "curvemesh/core/error.hpp"
#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/classification.hpp"

namespace cm::io {

namespace {
std::string lower_extension(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}
}  // namespace

FileFormat format_from_path(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == "msh") return FileFormat::kMsh;
  if (ext == "mesh") return FileFormat::kMedit;
  if (ext == "meshb") return FileFormat::kMeditBinary;
  if (ext == "vtu") return FileFormat::kVtu;
  if (ext == "sol") return FileFormat::kSol;
  if (ext == "solb") return FileFormat::kSolBinary;
  throw InputError(path, -1, -1,
                   fmt::format("unknown file extension '{}' (expected .msh, .mesh, .meshb, .vtu)", ext));
}

mesh::TetMesh read_mesh(const std::string& path) {
  const FileFormat format = format_from_path(path);
  mesh::TetMesh m;
  switch (format) {
    case FileFormat::kMsh: m = read_msh(read_file_bytes(path), path); break;
    case FileFormat::kMedit:
    case FileFormat::kMeditBinary: m = read_medit(read_file_bytes(path), path); break;
    case FileFormat::kVtu: throw InputError(path, -1, -1, ".vtu is an output format only; read .msh, .mesh or .meshb");
    default: throw InputError(path, -1, -1, "this is a solution file, not a mesh");
  }
  if (m.num_tets() == 0) throw InputError(path, -1, -1, "the file holds no tetrahedra");
  m.resize_vertex_arrays();
  mesh::build_adjacency(m);
  mesh::derive_classification(m);
  return m;
}

void write_mesh(const mesh::TetMesh& m, const std::string& path, const WriteOptions& options) {
  switch (format_from_path(path)) {
    case FileFormat::kMsh: write_msh41(m, path, options.binary); break;
    case FileFormat::kMedit: write_medit(m, path, false); break;
    case FileFormat::kMeditBinary: write_medit(m, path, true); break;
    case FileFormat::kVtu: write_vtu(m, path, options.cell_fields); break;
    default: throw InputError(path, -1, -1, "cannot write a mesh to a solution file (.sol/.solb)");
  }
}

}  // namespace cm::io

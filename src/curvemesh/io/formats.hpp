#pragma once
// One reader/writer per file format. Readers parse untrusted bytes: any
// malformed input raises cm::InputError naming the file, the line (text) or
// byte offset (binary) and the reason; they never crash or hang. Readers fill
// coords, tet2verts, tet_region and whatever classification the format holds
// (tris, edges, vert_class, vert_param, entities, high_order); they do not
// build adjacency nor derive missing classification (mesh_io.hpp does).
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::io {

/// Gmsh MSH 4.1 (ASCII or binary) and MSH 2.2 (ASCII or binary), detected
/// from $MeshFormat.
mesh::TetMesh read_msh(std::string_view bytes, const std::string& file_name);
/// Gmsh MSH 4.1 with $Entities, parametric $Nodes and $Elements.
void write_msh41(const mesh::TetMesh& m, const std::string& path, bool binary);

/// Medit .mesh (ASCII) and .meshb (binary), detected from the content.
mesh::TetMesh read_medit(std::string_view bytes, const std::string& file_name);
/// Writes .meshb when binary, else .mesh.
void write_medit(const mesh::TetMesh& m, const std::string& path, bool binary);

/// Per-tet data written as VTU cell data besides region and classification.
struct CellField {
  std::string name;
  std::vector<double> values;  ///< one per tet
};
/// VTK XML unstructured grid: linear tets, or VTK_LAGRANGE_TETRAHEDRON /
/// VTK_LAGRANGE_TRIANGLE for order >= 2. Cells: tets, then classified tris.
void write_vtu(const mesh::TetMesh& m, const std::string& path, std::span<const CellField> fields = {});

/// A solution field in MMG's .sol conventions, one entry per vertex.
struct SolField {
  enum class Type { kScalar = 1, kTensor = 3 };
  Type type = Type::kScalar;
  /// Scalar: 1 value per vertex. Tensor: 6 per vertex in MMG order
  /// (m11, m12, m22, m13, m23, m33).
  std::vector<double> values;
  std::size_t num_verts() const { return values.size() / (type == Type::kScalar ? 1 : 6); }
};
/// .sol (ASCII) or .solb (binary); the first field of type scalar or
/// symmetric tensor at vertices is read.
SolField read_sol(std::string_view bytes, const std::string& file_name);
void write_sol(const SolField& sol, const std::string& path, bool binary);

}  // namespace cm::io

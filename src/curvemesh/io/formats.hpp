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

/// Medit .mesh (ASCII) and .meshb (binary, libMeshb versions 1-4, either
/// byte order), detected from the content. Reads Vertices, Edges, Triangles
/// and Tetrahedra in any order; element references become edge_tag,
/// face_tag and tet_region; vertex references are ignored (vert_class stays
/// unclassified). Other keywords are skipped. Refuses Dimension 2 and the
/// high-order keywords (EdgesP2, TrianglesP2, TetrahedraP2, ...), whose node
/// order the format leaves open. A text file must end with End. O(size).
mesh::TetMesh read_medit(std::string_view bytes, const std::string& file_name);
/// Writes .meshb (version 2; 3 above 2 GB, 4 when counts need 64 bits) when
/// binary, else .mesh with coordinates that read back bit for bit. Vertex
/// references are the vertex classification tags (0 if unclassified).
/// Throws std::runtime_error for a mesh of order > 1 ("Medit format holds
/// linear meshes only").
void write_medit(const mesh::TetMesh& m, const std::string& path, bool binary);

/// Per-tet data written as VTU cell data besides region and classification.
struct CellField {
  std::string name;
  std::vector<double> values;  ///< one per tet
};
/// VTK XML unstructured grid: linear tets, or VTK_LAGRANGE_TETRAHEDRON /
/// VTK_LAGRANGE_TRIANGLE for order >= 2 in VTK's node order (points: the
/// mesh vertices, then one per distinct edge / face node). Cells: tets, then
/// classified tris. Cell data: "region" and "model_tag" (tet region or
/// triangle face tag), "dim" (3 or 2), then each field (NaN on triangles).
/// Point data: "class_dim" and "class_tag" of each point's classification
/// (-1 and 0 for an unclassified vertex). Arrays are raw binary in one
/// appended block. Throws std::invalid_argument for a field whose size is
/// not the number of tets or whose name is already used.
void write_vtu(const mesh::TetMesh& m, const std::string& path, std::span<const CellField> fields = {});

/// Any VTK unstructured grid, for data that is not a mesh (octree cells,
/// sample point clouds): points, cells by VTK type with VTK's offsets (where
/// each cell's connectivity ends), and Float64 point and cell fields of 1 or
/// 3 components. Written like write_vtu (raw appended block, atomically).
struct VtuGrid {
  struct Field {
    std::string name;
    int components = 1;          ///< 1 or 3
    std::vector<double> values;  ///< components per point (or cell)
  };
  std::vector<Vec3> points;
  std::vector<std::int64_t> connectivity;
  std::vector<std::int64_t> offsets;
  std::vector<std::uint8_t> types;
  std::vector<Field> point_fields, cell_fields;
};
/// Throws std::invalid_argument when sizes disagree, a field name repeats, or
/// a cell refers to a point that does not exist.
void write_vtu_grid(const VtuGrid& grid, const std::string& path);

/// A solution field in MMG's .sol conventions, one entry per vertex.
struct SolField {
  enum class Type { kScalar = 1, kTensor = 3 };
  Type type = Type::kScalar;
  /// Scalar: 1 value per vertex. Tensor: 6 per vertex in MMG order
  /// (m11, m12, m22, m13, m23, m33).
  std::vector<double> values;
  std::size_t num_verts() const { return values.size() / (type == Type::kScalar ? 1 : 6); }
};
/// .sol (ASCII) or .solb (binary, versions 1-4), detected from the content;
/// the first field of type scalar or symmetric tensor of SolAtVertices is
/// read (other fields are skipped). Dimension must be 3 and every value
/// finite. The caller checks num_verts() against its mesh.
SolField read_sol(std::string_view bytes, const std::string& file_name);
/// Writes one SolAtVertices field (.solb version 2, or 3 / 4 as for meshes).
/// Throws std::invalid_argument for a partial tensor or a non-finite value.
void write_sol(const SolField& sol, const std::string& path, bool binary);

}  // namespace cm::io

#pragma once
// Consistency checks of a tet mesh: the definition of a valid mesh in
// DESIGN.md, as far as it can be checked without the geometric model.
#include <cstdint>
#include <string>
#include <vector>

#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::mesh {

enum class Level {
  kTopology,  ///< adjacency symmetry, exact positive orientation, conformity
  kFull,      ///< plus classification consistency
};

struct ValidationIssue {
  enum class Kind {
    kInverted,             ///< tet with orient3d < 0
    kFlat,                 ///< tet with orient3d == 0 (exactly)
    kBadVertexId,          ///< tet references a vertex out of range
    kDuplicateVertex,      ///< tet uses the same vertex twice
    kAdjacencyAsymmetric,  ///< tet2adj[a] = b but tet2adj[b] != a
    kAdjacencyWrongFace,   ///< neighbours that do not share the face
    kNonManifoldFace,      ///< face shared by more than two tets
    kUnclassifiedBoundary, ///< hull or region-interface face missing from tris
    kTriNotOnMesh,         ///< classified triangle that is no tet face
    kClassification,       ///< classification rule broken (see message)
  };
  Kind kind;
  std::int64_t entity;  ///< tet id, packed face or vertex id, per kind
  std::string message;
};

struct ValidationReport {
  std::vector<ValidationIssue> issues;  ///< at most max_issues stored
  std::size_t num_issues = 0;           ///< all issues found
  std::size_t num_inverted = 0;
  std::size_t num_flat = 0;
  std::size_t num_nonconforming = 0;
  std::size_t num_classification = 0;
  bool valid() const { return num_issues == 0; }
};

/// Checks the mesh. Orientation uses the exact orient3d predicate. Needs
/// tet2adj to be built (it is checked against tet2verts). Linear in the mesh
/// size apart from an O(F log F) sort of boundary faces.
ValidationReport validate(const TetMesh& m, Level level, std::size_t max_issues = 1000);

std::string to_string(ValidationIssue::Kind kind);

}  // namespace cm::mesh

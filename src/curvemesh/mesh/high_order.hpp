#pragma once
// Storage of high-order (Lagrange) nodes per mesh edge and per mesh face, and
// the node order of order-p elements inside curvemesh.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <optional>
#include <vector>

#include "curvemesh/core/types.hpp"

namespace cm::mesh {

inline constexpr int kMaxOrder = 3;

/// Nodes of an order-p tet, (p+1)(p+2)(p+3)/6 (the 4 vertices for p < 1).
constexpr std::size_t tet_node_count(int p) { return p >= 1 ? std::size_t((p + 1) * (p + 2) * (p + 3) / 6) : 4; }
inline constexpr std::size_t kMaxTetNodes = tet_node_count(kMaxOrder);

/// Barycentric multi-indices (i0,i1,i2,i3), i0+..+i3 = p, of the nodes of an
/// order-p Lagrange tet in curvemesh's internal order: the 4 vertices; then for
/// each edge e in kTetEdges order its p-1 nodes from kTetEdges[e][0] to
/// kTetEdges[e][1]; then for each face f in kFaceVerts order its interior nodes
/// (ordered as tri_node_indices orders a triangle's interior nodes, relative to
/// the face's vertex list); then the interior nodes. Index k of the multi-index
/// is the weight of local vertex k. Size (p+1)(p+2)(p+3)/6.
std::vector<std::array<int, 4>> tet_node_indices(int p);

/// Same for a triangle: 3 vertices, edges (0,1),(1,2),(2,0) each from first to
/// second vertex, then interior nodes in decreasing lexicographic order of
/// (i0, i1). Size (p+1)(p+2)/2.
std::vector<std::array<int, 3>> tri_node_indices(int p);

/// High-order nodes keyed by the vertex ids of the edge / face they belong to.
/// Edges and faces without stored nodes are straight (nodes interpolated
/// linearly). Order 1 means a linear mesh (nothing stored).
class HighOrderNodes {
 public:
  int order() const { return order_; }
  /// Clears all nodes and sets the order (1..kMaxOrder; throws otherwise).
  void reset(int order);

  /// Stores the p-1 nodes of edge (a,b), listed from a to b.
  void set_edge(VertId a, VertId b, std::span<const Vec3> nodes_from_a);
  /// Writes the p-1 nodes from a to b into out; false if the edge has none.
  bool get_edge(VertId a, VertId b, Vec3* out_from_a) const;

  /// Stores the interior nodes of triangle (a,b,c), ordered as the interior
  /// entries of tri_node_indices(p) relative to (a,b,c).
  void set_face(VertId a, VertId b, VertId c, std::span<const Vec3> nodes);
  bool get_face(VertId a, VertId b, VertId c, Vec3* out) const;

  bool has_edge(VertId a, VertId b) const;
  bool has_face(VertId a, VertId b, VertId c) const;
  /// Forgets the nodes of edge (a,b) / face (a,b,c), which become straight.
  /// No effect when none are stored. Their slots are reused by later sets.
  void erase_edge(VertId a, VertId b);
  void erase_face(VertId a, VertId b, VertId c);

  /// Renames vertices by old2new, which must keep their order (as a
  /// compaction does); entries on a vertex mapped to kNone are dropped.
  void remap_vertices(std::span<const VertId> old2new);

  /// While set, set_edge, erase_edge, set_face and erase_face append the
  /// entity they are given to *journal (sorted vertex ids; an edge's third
  /// is kNone), whether or not its nodes change: with a copy taken before,
  /// a caller finds what an algorithm changed by comparing those entities
  /// alone. reset and remap_vertices are not journaled. A copy of this
  /// object does not journal.
  void set_journal(std::vector<std::array<VertId, 3>>* journal) { journal_.to = journal; }

  std::size_t num_edges() const { return edge_slot_.size; }
  std::size_t num_faces() const { return face_slot_.size; }
  std::size_t nodes_per_edge() const { return order_ > 1 ? order_ - 1 : 0; }
  std::size_t nodes_per_face() const {
    return order_ > 2 ? static_cast<std::size_t>((order_ - 1) * (order_ - 2) / 2) : 0;
  }

 private:
  // Where each entity's nodes are: open addressing on sorted vertex
  // triples (an edge is (a, b, kNone)), backward-shift erasure. Every tet
  // check looks up six edges and four faces, so the table is flat.
  struct SlotTable {
    static constexpr std::uint32_t kEmpty = 0xffffffffu;
    struct Entry {
      std::array<VertId, 3> key{kNone, kNone, kNone};
      std::uint32_t slot = kEmpty;
    };
    std::vector<Entry> entries;  // size a power of two, at most half full
    std::size_t size = 0;
    const std::uint32_t* find(const std::array<VertId, 3>& key) const;
    /// The slot of key (inserted with an unset slot if absent), and
    /// whether it was inserted.
    std::pair<std::uint32_t*, bool> insert(const std::array<VertId, 3>& key);
    std::optional<std::uint32_t> erase(const std::array<VertId, 3>& key);
    void grow();
    void clear();
  };
  static std::uint32_t take_slot(std::vector<std::uint32_t>& free, std::vector<Vec3>& nodes, std::size_t n);

  int order_ = 1;
  SlotTable edge_slot_;
  std::vector<Vec3> edge_nodes_;
  SlotTable face_slot_;
  std::vector<Vec3> face_nodes_;
  // Slots of erased entries, reused first: curving repairs erase and set
  // nodes many times over.
  std::vector<std::uint32_t> free_edge_slots_, free_face_slots_;
  struct Journal {
    std::vector<std::array<VertId, 3>>* to = nullptr;
    Journal() = default;
    Journal(const Journal&) {}
    Journal& operator=(const Journal&) { return *this; }
  };
  Journal journal_;
};

struct TetMesh;

/// All nodes of tet t in the internal order of tet_node_indices(order): stored
/// edge/face nodes where present, linear interpolation elsewhere.
std::vector<Vec3> gather_tet_nodes(const TetMesh& m, TetId t);
/// The same for a tet given by its vertices (it need not be in the mesh: a
/// tet an operator would create).
std::vector<Vec3> gather_tet_nodes(const TetMesh& m, const std::array<VertId, 4>& verts);
/// A tet's nodes in a buffer that fits any order: what the checks of a
/// curved mesh gather per tet, without an allocation.
struct TetNodes {
  std::array<Vec3, kMaxTetNodes> buffer;
  std::size_t count = 0;
  bool stored = false;  ///< whether any node came from storage (false: straight-sided)
  std::span<const Vec3> view() const { return {buffer.data(), count}; }
};
/// The nodes of the tet with these vertices, as gather_tet_nodes gives them.
TetNodes tet_nodes(const TetMesh& m, const std::array<VertId, 4>& verts);
/// All nodes of triangle (a,b,c) in the order of tri_node_indices(order).
std::vector<Vec3> gather_tri_nodes(const TetMesh& m, const std::array<VertId, 3>& tri);

/// Stores, from the full node list of tet t (internal order), the edge and face
/// nodes into m.high_order (the inverse of gather_tet_nodes).
void scatter_tet_nodes(TetMesh& m, TetId t, std::span<const Vec3> nodes);
void scatter_tri_nodes(TetMesh& m, const std::array<VertId, 3>& tri, std::span<const Vec3> nodes);

}  // namespace cm::mesh

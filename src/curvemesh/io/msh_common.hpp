#pragma once
// Private to the Gmsh MSH reader and writer (msh_read.cpp, msh41_read.cpp,
// msh22_read.cpp, msh41_write.cpp): the byte cursor that reports errors at a
// line (text files) or byte offset (binary files), the element types we
// accept, the node-order permutations between Gmsh and curvemesh, and the raw
// data both parsers hand to the shared mesh assembly.
#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "curvemesh/core/error.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::io::msh {

/// Where an item starts: its line (1-based) in a text file, its byte offset
/// in a binary one. Errors found after parsing use the stored position.
using Position = std::int64_t;

/// Reads a file held in memory, either as whitespace-separated text tokens or
/// as raw binary values, and throws cm::InputError at the start of the last
/// item read. Every read checks the remaining bytes first, so no input makes
/// it read out of bounds, and every count a caller allocates for is checked
/// against the bytes left (check_count), so an absurd count fails fast.
class Cursor {
 public:
  Cursor(std::string_view bytes, const std::string& file_name) : bytes_(bytes), file_(file_name) {}

  /// From now on report byte offsets and, if `swap`, byte-swap binary values
  /// (a file written on a machine of the other endianness).
  void set_binary(bool swap) {
    binary_ = true;
    swap_ = swap;
  }
  bool binary() const { return binary_; }
  const std::string& file_name() const { return file_; }

  /// Position of the last item read (line or byte offset, see Position).
  Position position() const { return binary_ ? static_cast<Position>(item_offset_) : item_line_; }
  [[noreturn]] void fail(const std::string& reason) const { fail_at(position(), reason); }
  [[noreturn]] void fail_at(Position pos, const std::string& reason) const;

  /// Skips whitespace; true when nothing but whitespace is left.
  bool at_end();
  /// Next whitespace-delimited token; fails with "unexpected end of file while
  /// reading <what>" if there is none.
  std::string_view next_token(const char* what);
  /// Next token, which must equal `expected`.
  void expect_token(std::string_view expected);
  /// After a text header line that precedes binary data: the rest of the line
  /// must be blank; consumes its newline so the binary data starts next.
  void end_line();
  /// Skips an unknown section "$Name" whose header token was just read, up to
  /// and including "$EndName". Linear in the skipped size.
  void skip_section(std::string_view name);

  // Values as text tokens (text files, and the text parts of binary files).
  std::int64_t text_int(const char* what, std::int64_t lo, std::int64_t hi);
  double text_double(const char* what, bool finite_only = true);

  // Values in the file's encoding: text tokens, or little/big-endian binary
  // of the given width. Sizes are size_t in MSH 4.1 (8 bytes; data-size 8).
  std::int32_t get_int(const char* what, std::int64_t lo = INT32_MIN, std::int64_t hi = INT32_MAX);
  std::uint64_t get_size(const char* what);
  /// A double; NaN and infinities are errors unless `finite_only` is false.
  double get_double(const char* what, bool finite_only = true);
  std::int32_t bin_int32(const char* what);

  /// Fails unless `count` items of at least `text_tokens` tokens (text) or
  /// `binary_bytes` bytes (binary) each fit in the rest of the file, and the
  /// count fits a 32-bit index.
  void check_count(std::uint64_t count, std::uint64_t text_tokens, std::uint64_t binary_bytes,
                   const char* what) const;

 private:
  void skip_whitespace();
  void require(std::size_t n, const char* what);
  template <class T>
  T read_binary(const char* what) {
    require(sizeof(T), what);
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, bytes_.data() + pos_, sizeof(T));
    if (swap_)
      for (std::size_t k = 0; k < sizeof(T) / 2; ++k) std::swap(raw[k], raw[sizeof(T) - 1 - k]);
    T value;
    std::memcpy(&value, raw, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }

  std::string_view bytes_;
  std::string file_;
  std::size_t pos_ = 0;
  std::int64_t line_ = 1;
  std::size_t item_offset_ = 0;
  std::int64_t item_line_ = 1;
  bool binary_ = false;
  bool swap_ = false;
};

/// A token as shown in an error message: printable characters, at most 32.
std::string quote(std::string_view token);

/// The element types curvemesh reads and writes.
enum class ElementKind { kPoint, kLine, kTri, kTet };

struct ElementType {
  int gmsh_type;
  ElementKind kind;
  int order;
  int num_nodes;
};

/// The accepted type, or nullptr for any other Gmsh type.
const ElementType* find_element_type(int gmsh_type);
/// Gmsh type number of `kind` at `order` (1..3).
int gmsh_type_of(ElementKind kind, int order);
/// "unsupported element type N (its name)" for an unknown type.
std::string unsupported_type_message(std::int64_t gmsh_type);
/// Dimension of an element kind (0..3).
int kind_dim(ElementKind kind);

/// For an order-p element of `kind`, entry k is the curvemesh-internal index
/// (mesh::tet_node_indices / tri_node_indices order; a line is its two ends
/// then its inner nodes from the first end) of the k-th node in Gmsh's order.
/// Gmsh lists tet edges as 0-1, 1-2, 2-0, 3-0, 3-2, 3-1 (inner nodes from the
/// first to the second vertex) and faces as 0-2-1, 0-1-3, 0-3-2, 3-1-2, while
/// curvemesh uses kTetEdges / kFaceVerts; triangles and lines agree.
const std::vector<int>& gmsh_to_internal(ElementKind kind, int order);

/// Node tag -> 0-based node index. Tags below a bound proportional to the
/// file size live in a dense array; larger (sparse) tags in a hash map, so
/// memory stays proportional to the input whatever the tags are.
class NodeTagMap {
 public:
  /// `expected_nodes` must already be checked against the file size.
  void reserve(std::uint64_t expected_nodes);
  /// False if the tag is already present.
  bool insert(std::uint64_t tag, Index node);
  Index find(std::uint64_t tag) const {
    if (tag < dense_.size()) return dense_[tag];
    auto it = sparse_.find(tag);
    return it == sparse_.end() ? kNone : it->second;
  }

 private:
  std::vector<Index> dense_;
  std::uint64_t dense_limit_ = 1 << 16;
  std::unordered_map<std::uint64_t, Index> sparse_;
};

/// The nodes of the file in file order.
struct RawNodes {
  std::vector<std::uint64_t> tags;
  std::vector<Vec3> coords;
  std::vector<mesh::ModelRef> entity;  ///< dim -1 when the format has none (2.2)
  std::vector<mesh::Param> param;
  NodeTagMap map;

  /// Appends a node; fails at `pos` (where its tag is) on a duplicate tag.
  void add(const Cursor& c, Position pos, std::uint64_t tag, const Vec3& x, mesh::ModelRef ref,
           const mesh::Param& p);
};

/// Elements of one kind in file order, nodes as node indices in Gmsh order.
struct RawElements {
  int nodes_per = 0;
  std::vector<Index> nodes;
  std::vector<std::int32_t> entity_tag;
  std::vector<std::uint64_t> tag;
  std::vector<Position> pos;
  std::size_t size() const { return tag.size(); }
};

struct RawMesh {
  RawNodes nodes;
  RawElements points, lines, tris, tets;
  int order = 0;  ///< of lines, triangles and tets; 0 until the first one
  std::vector<mesh::EntityInfo> entities;

  /// Checks that `type` may be added (orders agree; fails at the cursor
  /// otherwise) and returns its storage.
  RawElements& begin_elements(Cursor& c, const ElementType& type);
  /// Adds one element given its node tags (Gmsh order); fails on an
  /// undefined node or a repeated corner node.
  void add_element(Cursor& c, RawElements& e, std::uint64_t tag, std::int32_t entity,
                   const std::uint64_t* node_tags, Position pos);
};

/// Builds the mesh: vertices are the nodes used as element corners, numbered
/// by increasing node tag; elements of each kind are ordered by element tag;
/// high-order nodes go to m.high_order (consistency between elements sharing
/// an edge or a face is checked).
mesh::TetMesh assemble_mesh(RawMesh&& raw, const Cursor& c);

/// Section parsers, called after $MeshFormat; the cursor is in binary mode
/// for binary files.
void parse_msh41(Cursor& c, RawMesh& raw);
void parse_msh22(Cursor& c, RawMesh& raw);

}  // namespace cm::io::msh

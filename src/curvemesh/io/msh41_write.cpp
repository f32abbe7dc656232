// Gmsh MSH 4.1 writing, ASCII or binary.
//
// Layout: node tags 1..#V are the vertices in id order, then the high-order
// nodes grouped by entity; element tags 1..M are the lines (m.edges), then
// triangles (m.tris), then tets, each in mesh order, grouped into one block
// per entity. The reader orders vertices and elements by tag, so a written
// mesh reads back in its own order.
#include <fmt/compile.h>

#include <algorithm>
#include <iterator>
#include <limits>
#include <map>
#include <numeric>
#include <unordered_map>

#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/io/msh_common.hpp"

namespace cm::io {

namespace {

using mesh::ModelRef;
using msh::ElementKind;

// Values in the file's encoding: text separated by spaces and lines, or
// native-endian binary (the $MeshFormat marker tells readers the order).
class Output {
 public:
  Output(AtomicFile& file, bool binary) : file_(file), binary_(binary) {
    buf_.reserve(kFlushBytes + 4096);
  }
  bool binary() const { return binary_; }

  void text(std::string_view s) {
    buf_.append(s);
    maybe_flush();
  }
  void size(std::uint64_t v) {
    if (binary_) return put_binary(v);
    const fmt::format_int digits(v);
    buf_.append(digits.data(), digits.data() + digits.size());
    buf_.push_back(' ');
  }
  void int32(std::int32_t v) {
    if (binary_) return put_binary(v);
    const fmt::format_int digits(v);
    buf_.append(digits.data(), digits.data() + digits.size());
    buf_.push_back(' ');
  }
  // fmt's shortest representation reads back to the same double.
  void real(double v) {
    if (binary_) return put_binary(v);
    fmt::format_to(fmt::appender(buf_), FMT_COMPILE("{} "), v);
  }
  /// Ends a text line (nothing in binary).
  void end_line() {
    if (!binary_) {
      if (buf_.size() > 0 && buf_.data()[buf_.size() - 1] == ' ') buf_.resize(buf_.size() - 1);
      buf_.push_back('\n');
    }
    maybe_flush();
  }
  void begin_section(std::string_view name) { text(fmt::format("${}\n", name)); }
  void end_section(std::string_view name) {
    text(fmt::format("{}$End{}\n", binary_ ? "\n" : "", name));
  }
  void flush() {
    file_.write(buf_.data(), buf_.size());
    buf_.clear();
  }

 private:
  static constexpr std::size_t kFlushBytes = 1 << 20;
  template <class T>
  void put_binary(T v) {
    const auto* p = reinterpret_cast<const char*>(&v);
    buf_.append(p, p + sizeof(T));
  }
  void maybe_flush() {
    if (buf_.size() >= kFlushBytes) flush();
  }

  AtomicFile& file_;
  bool binary_;
  fmt::memory_buffer buf_;
};

struct Entity {
  ModelRef ref;
  std::vector<std::int32_t> bounding;
  std::vector<std::int32_t> physicals;
  bool derive_bounding = true;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());
  void grow(const Vec3& x) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
};

// Items 0..n-1 grouped by key (0..k-1), each group in increasing item order.
struct Groups {
  std::vector<Index> start;  // k+1 offsets into items
  std::vector<Index> items;
};

Groups group_by(const std::vector<Index>& key, std::size_t k) {
  Groups g;
  g.start.assign(k + 1, 0);
  for (Index e : key) ++g.start[e + 1];
  std::partial_sum(g.start.begin(), g.start.end(), g.start.begin());
  g.items.resize(key.size());
  std::vector<Index> fill(g.start.begin(), g.start.end() - 1);
  for (Index i = 0; i < key.size(); ++i) g.items[fill[key[i]]++] = i;
  return g;
}

std::uint64_t edge_key(VertId a, VertId b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

std::array<VertId, 3> sorted3(VertId a, VertId b, VertId c) {
  std::array<VertId, 3> s{a, b, c};
  std::sort(s.begin(), s.end());
  return s;
}

struct Tri3Hash {
  std::size_t operator()(const std::array<VertId, 3>& k) const {
    std::uint64_t h = k[0];
    h = h * 0x9E3779B97F4A7C15ull ^ k[1];
    h = h * 0x9E3779B97F4A7C15ull ^ k[2];
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

// Everything the sections need, computed before anything is written.
class Layout {
 public:
  explicit Layout(const mesh::TetMesh& m) : m_(m), p_(m.high_order.order()) {
    check_input();
    classify_vertices();
    collect_entities();
    if (p_ > 1) number_high_order_nodes();
    derive_bounding();
    compute_boxes();
  }

  void write(Output& out) const {
    write_header(out);
    write_entities(out);
    write_nodes(out);
    write_elements(out);
  }

 private:
  void check_input() const {
    const std::size_t nv = m_.num_verts();
    CM_ASSERT_OP(m_.tet_region.size(), ==, m_.num_tets());
    CM_ASSERT_OP(m_.vert_class.size(), ==, nv);
    CM_ASSERT_OP(m_.vert_param.size(), ==, nv);
    for (const auto& t : m_.tet2verts)
      for (VertId v : t) CM_ASSERT_OP(v, <, nv);
    for (const auto& t : m_.tris)
      for (VertId v : t.verts) CM_ASSERT_OP(v, <, nv);
    for (const auto& e : m_.edges)
      for (VertId v : e.verts) CM_ASSERT_OP(v, <, nv);
    CM_ASSERT_OP(m_.high_order.nodes_per_face(), <=, 1u);  // orders 1..3
  }

  // The entity of each vertex's node: its classification, else the region of
  // its lowest-numbered tet, else the entity of its first triangle or edge,
  // else a volume of its own (a vertex in no element).
  void classify_vertices() {
    vert_ref_ = m_.vert_class;
    std::vector<std::size_t> unplaced;
    for (VertId v = 0; v < vert_ref_.size(); ++v)
      if (!vert_ref_[v].valid()) unplaced.push_back(v);
    if (unplaced.empty()) return;
    std::vector<ModelRef> fallback(m_.num_verts());
    const auto offer = [&](VertId v, ModelRef r) {
      if (!fallback[v].valid()) fallback[v] = r;
    };
    for (TetId t = 0; t < m_.num_tets(); ++t)
      for (VertId v : m_.tet2verts[t]) offer(v, {3, m_.tet_region[t]});
    for (const auto& t : m_.tris)
      for (VertId v : t.verts) offer(v, {2, t.face_tag});
    for (const auto& e : m_.edges)
      for (VertId v : e.verts) offer(v, {1, e.edge_tag});
    std::int32_t orphan_tag = 0;
    for (std::int32_t r : m_.tet_region) orphan_tag = std::max(orphan_tag, r);
    for (const auto& e : m_.entities)
      if (e.dim == 3) orphan_tag = std::max(orphan_tag, e.tag);
    for (std::size_t v : unplaced)
      vert_ref_[v] = fallback[v].valid() ? fallback[v] : ModelRef{3, orphan_tag + 1};
  }

  std::size_t entity_index(ModelRef r) const { return entity_index_.at(r); }

  void collect_entities() {
    std::map<ModelRef, const mesh::EntityInfo*> given;
    for (const auto& e : m_.entities) given.try_emplace(ModelRef{e.dim, e.tag}, &e);
    std::map<ModelRef, int> used;
    for (const auto& [ref, info] : given) used[ref];
    for (const ModelRef& r : vert_ref_) used[r];
    for (const auto& e : m_.edges) used[{1, e.edge_tag}];
    for (const auto& t : m_.tris) used[{2, t.face_tag}];
    for (std::int32_t r : m_.tet_region) used[{3, r}];
    for (const auto& [ref, unused] : used) {
      Entity e;
      e.ref = ref;
      if (auto it = given.find(ref); it != given.end()) {
        e.physicals = it->second->physicals;
        e.bounding = it->second->bounding;
        e.derive_bounding = ref.dim > 0 && e.bounding.empty();
      } else {
        e.derive_bounding = ref.dim > 0;
      }
      entity_index_[ref] = entities_.size();
      entities_.push_back(std::move(e));
    }
    vert_entity_.resize(m_.num_verts());
    for (VertId v = 0; v < m_.num_verts(); ++v)
      vert_entity_[v] = static_cast<Index>(entity_index(vert_ref_[v]));
    edge_entity_ = entity_indices(m_.edges.size(), [&](std::size_t i) {
      return ModelRef{1, m_.edges[i].edge_tag};
    });
    tri_entity_ = entity_indices(m_.tris.size(), [&](std::size_t i) {
      return ModelRef{2, m_.tris[i].face_tag};
    });
    tet_entity_ = entity_indices(m_.num_tets(), [&](std::size_t i) {
      return ModelRef{3, m_.tet_region[i]};
    });
  }

  template <class RefOf>
  std::vector<Index> entity_indices(std::size_t n, RefOf ref_of) const {
    std::vector<Index> out(n);
    ModelRef last{};
    Index last_index = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const ModelRef r = ref_of(i);
      if (i == 0 || r != last) last_index = static_cast<Index>(entity_index(r));
      last = r;
      out[i] = last_index;
    }
    return out;
  }

  // Bounding entities of the entities not described by m.entities: the model
  // vertices at the ends of a curve's edges, the curves along a surface's
  // triangles, the surfaces on a volume's tet faces (unsigned).
  void derive_bounding() {
    std::vector<std::pair<Index, std::int32_t>> pairs;
    const auto need = [&](Index e) { return entities_[e].derive_bounding; };
    for (std::size_t i = 0; i < m_.edges.size(); ++i)
      if (need(edge_entity_[i]))
        for (VertId v : m_.edges[i].verts)
          if (vert_ref_[v].dim == 0) pairs.emplace_back(edge_entity_[i], vert_ref_[v].tag);
    const bool tris_need =
        std::any_of(tri_entity_.begin(), tri_entity_.end(), need) && !m_.edges.empty();
    if (tris_need) {
      std::unordered_map<std::uint64_t, std::int32_t> curve_of;
      for (const auto& e : m_.edges)
        curve_of.try_emplace(edge_key(e.verts[0], e.verts[1]), e.edge_tag);
      for (std::size_t i = 0; i < m_.tris.size(); ++i)
        if (need(tri_entity_[i]))
          for (const auto& k : mesh::kTriEdges) {
            const auto& v = m_.tris[i].verts;
            if (auto it = curve_of.find(edge_key(v[k[0]], v[k[1]])); it != curve_of.end())
              pairs.emplace_back(tri_entity_[i], it->second);
          }
    }
    const bool tets_need =
        std::any_of(tet_entity_.begin(), tet_entity_.end(), need) && !m_.tris.empty();
    if (tets_need) {
      std::unordered_map<std::array<VertId, 3>, std::int32_t, Tri3Hash> surface_of;
      for (const auto& t : m_.tris)
        surface_of.try_emplace(sorted3(t.verts[0], t.verts[1], t.verts[2]), t.face_tag);
      for (TetId t = 0; t < m_.num_tets(); ++t)
        if (need(tet_entity_[t]))
          for (const auto& f : mesh::kFaceVerts) {
            const auto& v = m_.tet2verts[t];
            if (auto it = surface_of.find(sorted3(v[f[0]], v[f[1]], v[f[2]]));
                it != surface_of.end())
              pairs.emplace_back(tet_entity_[t], it->second);
          }
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    for (const auto& [e, tag] : pairs) entities_[e].bounding.push_back(tag);
  }

  void compute_boxes() {
    for (VertId v = 0; v < m_.num_verts(); ++v) entities_[vert_entity_[v]].grow(m_.coords[v]);
    for (std::size_t i = 0; i < m_.edges.size(); ++i)
      for (VertId v : m_.edges[i].verts) entities_[edge_entity_[i]].grow(m_.coords[v]);
    for (std::size_t i = 0; i < m_.tris.size(); ++i)
      for (VertId v : m_.tris[i].verts) entities_[tri_entity_[i]].grow(m_.coords[v]);
    for (TetId t = 0; t < m_.num_tets(); ++t)
      for (VertId v : m_.tet2verts[t]) entities_[tet_entity_[t]].grow(m_.coords[v]);
    for (std::size_t k = 0; k < ho_coords_.size(); ++k)
      entities_[ho_entity_[k]].grow(ho_coords_[k]);
  }

  // Edges (and, at order 3, faces) of all elements, numbered in increasing
  // vertex order; each gets the entity of its first occurrence, listing
  // m.edges, then triangles, then tets, so a curve wins over a surface and a
  // surface over a volume. Their nodes are then numbered entity by entity.
  void number_high_order_nodes() {
    const std::size_t ne = m_.edges.size(), nf = m_.tris.size(), nt = m_.num_tets();
    struct EdgeOcc {
      std::uint64_t key;
      std::uint64_t occ;
    };
    std::vector<EdgeOcc> occ;
    occ.reserve(ne + 3 * nf + 6 * nt);
    for (const auto& e : m_.edges) occ.push_back({edge_key(e.verts[0], e.verts[1]), occ.size()});
    for (const auto& t : m_.tris)
      for (const auto& k : mesh::kTriEdges)
        occ.push_back({edge_key(t.verts[k[0]], t.verts[k[1]]), occ.size()});
    for (const auto& t : m_.tet2verts)
      for (const auto& k : mesh::kTetEdges) occ.push_back({edge_key(t[k[0]], t[k[1]]), occ.size()});
    std::sort(occ.begin(), occ.end(), [](const EdgeOcc& a, const EdgeOcc& b) {
      return a.key != b.key ? a.key < b.key : a.occ < b.occ;
    });
    occ2edge_.resize(occ.size());
    std::vector<std::uint64_t> edge_keys;
    std::vector<Index> edge_entity;
    for (std::size_t i = 0; i < occ.size(); ++i) {
      if (i == 0 || occ[i].key != occ[i - 1].key) {
        edge_keys.push_back(occ[i].key);
        const std::uint64_t o = occ[i].occ;
        edge_entity.push_back(o < ne            ? edge_entity_[o]
                              : o < ne + 3 * nf ? tri_entity_[(o - ne) / 3]
                                                : tet_entity_[(o - ne - 3 * nf) / 6]);
      }
      occ2edge_[occ[i].occ] = static_cast<Index>(edge_keys.size() - 1);
    }
    std::vector<EdgeOcc>().swap(occ);

    struct FaceOcc {
      std::array<VertId, 3> key;
      Index occ;
    };
    std::vector<std::array<VertId, 3>> face_keys;
    std::vector<Index> face_entity;
    if (m_.high_order.nodes_per_face() > 0) {
      std::vector<FaceOcc> focc;
      focc.reserve(nf + 4 * nt);
      for (const auto& t : m_.tris)
        focc.push_back(
            {sorted3(t.verts[0], t.verts[1], t.verts[2]), static_cast<Index>(focc.size())});
      for (const auto& t : m_.tet2verts)
        for (const auto& f : mesh::kFaceVerts)
          focc.push_back({sorted3(t[f[0]], t[f[1]], t[f[2]]), static_cast<Index>(focc.size())});
      std::sort(focc.begin(), focc.end(), [](const FaceOcc& a, const FaceOcc& b) {
        return a.key != b.key ? a.key < b.key : a.occ < b.occ;
      });
      occ2face_.resize(focc.size());
      for (std::size_t i = 0; i < focc.size(); ++i) {
        if (i == 0 || focc[i].key != focc[i - 1].key) {
          face_keys.push_back(focc[i].key);
          const Index o = focc[i].occ;
          face_entity.push_back(o < nf ? tri_entity_[o] : tet_entity_[(o - nf) / 4]);
        }
        occ2face_[focc[i].occ] = static_cast<Index>(face_keys.size() - 1);
      }
    }

    // Node tags: after the vertices, entity by entity, edges before faces.
    const std::size_t per_edge = m_.high_order.nodes_per_edge();
    const std::size_t per_face = m_.high_order.nodes_per_face();
    std::vector<Index> item_entity(edge_entity);
    item_entity.insert(item_entity.end(), face_entity.begin(), face_entity.end());
    const Groups groups = group_by(item_entity, entities_.size());
    edge_first_tag_.resize(edge_keys.size());
    face_first_tag_.resize(face_keys.size());
    std::vector<Vec3> buf(per_edge + per_face + 1);
    ho_block_start_.assign(entities_.size() + 1, 0);
    for (std::size_t e = 0; e < entities_.size(); ++e) {
      ho_block_start_[e] = ho_coords_.size();
      for (Index k = groups.start[e]; k < groups.start[e + 1]; ++k) {
        const Index item = groups.items[k];
        const std::uint64_t first_tag = m_.num_verts() + ho_coords_.size() + 1;
        if (item < edge_keys.size()) {
          edge_first_tag_[item] = first_tag;
          const auto a = static_cast<VertId>(edge_keys[item] >> 32);
          const auto b = static_cast<VertId>(edge_keys[item] & 0xffffffffu);
          if (!m_.high_order.get_edge(a, b, buf.data()))
            for (std::size_t s = 0; s < per_edge; ++s)
              buf[s] =
                  m_.coords[a] + (static_cast<double>(s + 1) / p_) * (m_.coords[b] - m_.coords[a]);
          ho_coords_.insert(ho_coords_.end(), buf.begin(),
                            buf.begin() + static_cast<std::ptrdiff_t>(per_edge));
          ho_entity_.insert(ho_entity_.end(), per_edge, static_cast<Index>(e));
        } else {
          const std::size_t f = item - edge_keys.size();
          face_first_tag_[f] = first_tag;
          const auto& v = face_keys[f];
          // At order 3 the one face node defaults to the centroid.
          if (!m_.high_order.get_face(v[0], v[1], v[2], buf.data()))
            buf[0] = (m_.coords[v[0]] + m_.coords[v[1]] + m_.coords[v[2]]) / 3.0;
          ho_coords_.push_back(buf[0]);
          ho_entity_.push_back(static_cast<Index>(e));
        }
      }
    }
    ho_block_start_[entities_.size()] = ho_coords_.size();
  }

  void write_header(Output& out) const {
    out.text("$MeshFormat\n");
    out.text(fmt::format("4.1 {} 8\n", out.binary() ? 1 : 0));
    if (out.binary()) {
      const std::int32_t one = 1;
      out.int32(one);
      out.text("\n");
    }
    out.text("$EndMeshFormat\n");
  }

  void write_entities(Output& out) const {
    out.begin_section("Entities");
    std::array<std::uint64_t, 4> counts{};
    for (const Entity& e : entities_) ++counts[static_cast<std::size_t>(e.ref.dim)];
    for (std::uint64_t c : counts) out.size(c);
    out.end_line();
    for (const Entity& e : entities_) {
      out.int32(e.ref.tag);
      const bool empty = !(e.lo.array() <= e.hi.array()).all();
      const Vec3 lo = empty ? Vec3::Zero() : e.lo;
      const Vec3 hi = empty ? Vec3::Zero() : e.hi;
      for (int k = 0; k < 3; ++k) out.real(lo[k]);
      if (e.ref.dim > 0)
        for (int k = 0; k < 3; ++k) out.real(hi[k]);
      out.size(e.physicals.size());
      for (std::int32_t t : e.physicals) out.int32(t);
      if (e.ref.dim > 0) {
        out.size(e.bounding.size());
        for (std::int32_t t : e.bounding) out.int32(t);
      }
      out.end_line();
    }
    out.end_section("Entities");
  }

  void write_nodes(Output& out) const {
    const Groups verts = group_by(vert_entity_, entities_.size());
    std::uint64_t num_blocks = 0;
    for (std::size_t e = 0; e < entities_.size(); ++e) {
      num_blocks += verts.start[e + 1] > verts.start[e];
      if (!ho_block_start_.empty()) num_blocks += ho_block_start_[e + 1] > ho_block_start_[e];
    }
    const std::uint64_t num_nodes = m_.num_verts() + ho_coords_.size();
    out.begin_section("Nodes");
    out.size(num_blocks);
    out.size(num_nodes);
    out.size(num_nodes > 0 ? 1 : 0);
    out.size(num_nodes);
    out.end_line();
    for (std::size_t e = 0; e < entities_.size(); ++e) {
      const auto first = verts.items.begin() + verts.start[e];
      const auto last = verts.items.begin() + verts.start[e + 1];
      if (first == last) continue;
      const int dim = entities_[e].ref.dim;
      const bool parametric =
          (dim == 1 || dim == 2) && std::all_of(first, last, [&](VertId v) {
            const mesh::Param& p = m_.vert_param[v];
            return m_.vert_class[v].valid() && p.has_u() && (dim == 1 || !std::isnan(p.v));
          });
      write_block_header(out, entities_[e].ref, parametric,
                         static_cast<std::uint64_t>(last - first));
      for (auto it = first; it != last; ++it) {
        out.size(*it + std::uint64_t{1});
        out.end_line();
      }
      for (auto it = first; it != last; ++it) {
        for (int k = 0; k < 3; ++k) out.real(m_.coords[*it][k]);
        if (parametric) out.real(m_.vert_param[*it].u);
        if (parametric && dim == 2) out.real(m_.vert_param[*it].v);
        out.end_line();
      }
    }
    for (std::size_t e = 0; e + 1 < ho_block_start_.size(); ++e) {
      const std::size_t first = ho_block_start_[e], last = ho_block_start_[e + 1];
      if (first == last) continue;
      write_block_header(out, entities_[e].ref, false, last - first);
      for (std::size_t k = first; k < last; ++k) {
        out.size(m_.num_verts() + k + 1);
        out.end_line();
      }
      for (std::size_t k = first; k < last; ++k) {
        for (int j = 0; j < 3; ++j) out.real(ho_coords_[k][j]);
        out.end_line();
      }
    }
    out.end_section("Nodes");
  }

  static void write_block_header(Output& out, ModelRef ref, bool parametric, std::uint64_t n) {
    out.int32(ref.dim);
    out.int32(ref.tag);
    out.int32(parametric ? 1 : 0);
    out.size(n);
    out.end_line();
  }

  // Node tags of element i of `kind` in curvemesh's internal order.
  void internal_tags(ElementKind kind, std::size_t i, std::vector<std::uint64_t>& tags) const {
    const std::size_t ne = m_.edges.size(), nf = m_.tris.size();
    const VertId* v = kind == ElementKind::kTet   ? m_.tet2verts[i].data()
                      : kind == ElementKind::kTri ? m_.tris[i].verts.data()
                                                  : m_.edges[i].verts.data();
    const int corners = msh::kind_dim(kind) + 1;
    tags.clear();
    for (int k = 0; k < corners; ++k) tags.push_back(v[k] + std::uint64_t{1});
    if (p_ == 1) return;
    const auto add_edge = [&](int a, int b, std::size_t occ) {
      const std::uint64_t first = edge_first_tag_[occ2edge_[occ]];
      const std::uint64_t n = static_cast<std::uint64_t>(p_ - 1);
      for (std::uint64_t s = 0; s < n; ++s)
        tags.push_back(v[a] < v[b] ? first + s : first + n - 1 - s);
    };
    if (kind == ElementKind::kLine) {
      add_edge(0, 1, i);
    } else if (kind == ElementKind::kTri) {
      for (std::size_t k = 0; k < 3; ++k)
        add_edge(mesh::kTriEdges[k][0], mesh::kTriEdges[k][1], ne + 3 * i + k);
      if (!occ2face_.empty()) tags.push_back(face_first_tag_[occ2face_[i]]);
    } else {
      for (std::size_t k = 0; k < 6; ++k)
        add_edge(mesh::kTetEdges[k][0], mesh::kTetEdges[k][1], ne + 3 * nf + 6 * i + k);
      if (!occ2face_.empty())
        for (std::size_t f = 0; f < 4; ++f)
          tags.push_back(face_first_tag_[occ2face_[nf + 4 * i + f]]);
    }
  }

  void write_elements(Output& out) const {
    const std::size_t ne = m_.edges.size(), nf = m_.tris.size(), nt = m_.num_tets();
    struct Kind {
      ElementKind kind;
      const std::vector<Index>* entity;
      std::uint64_t first_tag;
    };
    const std::array<Kind, 3> kinds{{{ElementKind::kLine, &edge_entity_, 1},
                                     {ElementKind::kTri, &tri_entity_, 1 + ne},
                                     {ElementKind::kTet, &tet_entity_, 1 + ne + nf}}};
    std::array<Groups, 3> groups;
    std::uint64_t num_blocks = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      groups[k] = group_by(*kinds[k].entity, entities_.size());
      for (std::size_t e = 0; e < entities_.size(); ++e)
        num_blocks += groups[k].start[e + 1] > groups[k].start[e];
    }
    const std::uint64_t num_elements = ne + nf + nt;
    out.begin_section("Elements");
    out.size(num_blocks);
    out.size(num_elements);
    out.size(num_elements > 0 ? 1 : 0);
    out.size(num_elements);
    out.end_line();
    std::vector<std::uint64_t> tags;
    for (std::size_t k = 0; k < 3; ++k) {
      const ElementKind kind = kinds[k].kind;
      const auto& perm = msh::gmsh_to_internal(kind, p_);
      for (std::size_t e = 0; e < entities_.size(); ++e) {
        const Index first = groups[k].start[e], last = groups[k].start[e + 1];
        if (first == last) continue;
        out.int32(entities_[e].ref.dim);
        out.int32(entities_[e].ref.tag);
        out.int32(msh::gmsh_type_of(kind, p_));
        out.size(last - first);
        out.end_line();
        for (Index j = first; j < last; ++j) {
          const Index i = groups[k].items[j];
          out.size(kinds[k].first_tag + i);
          internal_tags(kind, i, tags);
          for (int slot : perm) out.size(tags[static_cast<std::size_t>(slot)]);
          out.end_line();
        }
      }
    }
    out.end_section("Elements");
  }

  const mesh::TetMesh& m_;
  const int p_;
  std::vector<ModelRef> vert_ref_;
  std::vector<Entity> entities_;
  std::map<ModelRef, std::size_t> entity_index_;
  std::vector<Index> vert_entity_, edge_entity_, tri_entity_, tet_entity_;
  // High-order nodes: occurrence -> edge / face id -> first node tag; the
  // nodes' coordinates and entities in tag order, and each entity's range.
  std::vector<Index> occ2edge_, occ2face_;
  std::vector<std::uint64_t> edge_first_tag_, face_first_tag_;
  std::vector<Vec3> ho_coords_;
  std::vector<Index> ho_entity_;
  std::vector<std::size_t> ho_block_start_;
};

}  // namespace

void write_msh41(const mesh::TetMesh& m, const std::string& path, bool binary) {
  const Layout layout(m);
  AtomicFile file(path);
  Output out(file, binary);
  layout.write(out);
  out.flush();
  file.commit();
}

}  // namespace cm::io

#include "curvemesh/mesh/validate.hpp"

#include <algorithm>
#include <cstdint>
#include <map>
#include <set>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"

namespace cm::mesh {

std::string to_string(ValidationIssue::Kind kind) {
  using K = ValidationIssue::Kind;
  switch (kind) {
    case K::kInverted: return "inverted tet";
    case K::kFlat: return "flat tet";
    case K::kBadVertexId: return "vertex id out of range";
    case K::kDuplicateVertex: return "repeated vertex in tet";
    case K::kAdjacencyAsymmetric: return "asymmetric adjacency";
    case K::kAdjacencyWrongFace: return "adjacency across non-matching faces";
    case K::kNonManifoldFace: return "face shared by more than two tets";
    case K::kUnclassifiedBoundary: return "boundary face without classification";
    case K::kTriNotOnMesh: return "classified triangle that is not a tet face";
    case K::kClassification: return "classification";
  }
  return "unknown";
}

namespace {

using Kind = ValidationIssue::Kind;

class Reporter {
 public:
  Reporter(ValidationReport& r, std::size_t max_issues) : report_(r), max_(max_issues) {}
  void add(Kind kind, std::int64_t entity, std::string message) {
    ++report_.num_issues;
    switch (kind) {
      case Kind::kInverted: ++report_.num_inverted; break;
      case Kind::kFlat: ++report_.num_flat; break;
      case Kind::kClassification: ++report_.num_classification; break;
      default: ++report_.num_nonconforming; break;
    }
    if (report_.issues.size() < max_) report_.issues.push_back({kind, entity, std::move(message)});
  }

 private:
  ValidationReport& report_;
  std::size_t max_;
};

using TriKey = std::array<VertId, 3>;
TriKey sorted_key(VertId a, VertId b, VertId c) {
  TriKey k{a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

// The per-tet and per-face tests run in parallel into status arrays; the
// issues are then reported in tet order, as a serial pass would.
bool check_tets(const TetMesh& m, Reporter& rep) {
  enum : std::uint8_t { kOk, kBadId, kDuplicate, kNegative, kZero };
  const auto nv = static_cast<VertId>(m.num_verts());
  std::vector<std::uint8_t> status(m.num_tets(), kOk);
  tbb::parallel_for(tbb::blocked_range<TetId>(0, static_cast<TetId>(m.num_tets()), 4096),
                    [&](const tbb::blocked_range<TetId>& r) {
                      for (TetId t = r.begin(); t != r.end(); ++t) {
                        const auto& v = m.tet2verts[t];
                        if (v[0] >= nv || v[1] >= nv || v[2] >= nv || v[3] >= nv) {
                          status[t] = kBadId;
                        } else if (v[0] == v[1] || v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3] ||
                                   v[2] == v[3]) {
                          status[t] = kDuplicate;
                        } else {
                          const int s = predicates::orient3d(m.coords[v[0]].data(), m.coords[v[1]].data(),
                                                             m.coords[v[2]].data(), m.coords[v[3]].data());
                          status[t] = s < 0 ? kNegative : s == 0 ? kZero : kOk;
                        }
                      }
                    });
  bool ids_ok = true;
  for (TetId t = 0; t < m.num_tets(); ++t) {
    switch (status[t]) {
      case kBadId:
        rep.add(Kind::kBadVertexId, t, fmt::format("tet {} references a vertex >= {}", t, nv));
        ids_ok = false;
        break;
      case kDuplicate: rep.add(Kind::kDuplicateVertex, t, fmt::format("tet {} uses a vertex twice", t)); break;
      case kNegative: rep.add(Kind::kInverted, t, fmt::format("tet {} is inverted (negative volume)", t)); break;
      case kZero: rep.add(Kind::kFlat, t, fmt::format("tet {} is flat (zero volume)", t)); break;
      default: break;
    }
  }
  return ids_ok;
}

void check_adjacency(const TetMesh& m, Reporter& rep) {
  if (m.tet2adj.size() != 4 * m.num_tets()) {
    rep.add(Kind::kAdjacencyAsymmetric, -1, "adjacency not built for all tets");
    return;
  }
  enum : std::uint8_t { kOk, kNoPointBack, kWrongFace };
  std::vector<std::uint8_t> status(m.tet2adj.size(), kOk);
  tbb::parallel_for(tbb::blocked_range<TetId>(0, static_cast<TetId>(m.num_tets()), 4096),
                    [&](const tbb::blocked_range<TetId>& r) {
                      for (TetId t = r.begin(); t != r.end(); ++t)
                        for (int f = 0; f < 4; ++f) {
                          const Index here = pack_face(t, f);
                          const Index there = m.tet2adj[here];
                          if (there == kNone) continue;
                          if (face_tet(there) >= m.num_tets() || m.tet2adj[there] != here) {
                            status[here] = kNoPointBack;
                            continue;
                          }
                          const auto& a = m.tet2verts[t];
                          const auto& b = m.tet2verts[face_tet(there)];
                          const int g = face_index(there);
                          if (sorted_key(a[kFaceVerts[f][0]], a[kFaceVerts[f][1]], a[kFaceVerts[f][2]]) !=
                              sorted_key(b[kFaceVerts[g][0]], b[kFaceVerts[g][1]], b[kFaceVerts[g][2]]))
                            status[here] = kWrongFace;
                        }
                    });
  for (TetId t = 0; t < m.num_tets(); ++t)
    for (int f = 0; f < 4; ++f) {
      const Index here = pack_face(t, f);
      if (status[here] == kNoPointBack)
        rep.add(Kind::kAdjacencyAsymmetric, here, fmt::format("tet {} face {}: neighbour does not point back", t, f));
      else if (status[here] == kWrongFace)
        rep.add(Kind::kAdjacencyWrongFace, here,
                fmt::format("tet {} face {}: neighbour {} does not share it", t, f, face_tet(m.tet2adj[here])));
    }
}

// Faces used by more than two tets are invisible to tet2adj (they stay
// unmatched), so conformity is checked on the sorted face list directly.
// Returns the boundary faces: hull faces and faces between different regions,
// each with the tet that owns it.
std::vector<std::pair<TriKey, Index>> check_conformity(const TetMesh& m, Reporter& rep) {
  // Keys are distinct (each carries its own face), so the parallel sort's
  // order is the serial one.
  std::vector<std::pair<TriKey, Index>> faces(4 * m.num_tets());
  tbb::parallel_for(tbb::blocked_range<TetId>(0, static_cast<TetId>(m.num_tets()), 4096),
                    [&](const tbb::blocked_range<TetId>& r) {
                      for (TetId t = r.begin(); t != r.end(); ++t) {
                        const auto& v = m.tet2verts[t];
                        for (int f = 0; f < 4; ++f)
                          faces[pack_face(t, f)] = {sorted_key(v[kFaceVerts[f][0]], v[kFaceVerts[f][1]], v[kFaceVerts[f][2]]),
                                                    pack_face(t, f)};
                      }
                    });
  tbb::parallel_sort(faces.begin(), faces.end());
  std::vector<std::pair<TriKey, Index>> boundary;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].first == faces[i].first) ++j;
    if (j - i > 2) {
      rep.add(Kind::kNonManifoldFace, faces[i].second,
              fmt::format("face ({}, {}, {}) is shared by {} tets", faces[i].first[0], faces[i].first[1], faces[i].first[2], j - i));
    } else if (j - i == 1) {
      boundary.push_back(faces[i]);
    } else if (m.tet_region[face_tet(faces[i].second)] != m.tet_region[face_tet(faces[i + 1].second)]) {
      boundary.push_back(faces[i]);
    } else if (m.tet2adj.size() == 4 * m.num_tets() && m.tet2adj[faces[i].second] != faces[i + 1].second) {
      rep.add(Kind::kAdjacencyAsymmetric, faces[i].second, fmt::format("tets {} and {} share a face but are not adjacent",
                                                                       face_tet(faces[i].second), face_tet(faces[i + 1].second)));
    }
    i = j;
  }
  return boundary;
}

// An embedded model face inside one region is not a boundary face; look for a
// tet of the first vertex's ball that has all three vertices.
bool is_tet_face(const TetMesh& m, const TriKey& key) {
  if (m.vert2tet.size() != m.num_verts() || m.tet2adj.size() != 4 * m.num_tets()) return false;
  std::vector<TetId> ball;
  collect_ball(m, key[0], ball);
  for (TetId t : ball)
    if (local_index(m, t, key[1]) >= 0 && local_index(m, t, key[2]) >= 0) return true;
  return false;
}

void check_classification(const TetMesh& m, const std::vector<std::pair<TriKey, Index>>& boundary, Reporter& rep) {
  const auto nv = m.num_verts();
  if (m.vert_class.size() != nv) {
    rep.add(Kind::kClassification, -1, "vertex classification array has the wrong size");
    return;
  }
  for (VertId v = 0; v < nv; ++v)
    if (m.vert_class[v].dim < 0 || m.vert_class[v].dim > 3)
      rep.add(Kind::kClassification, v, fmt::format("vertex {} is not classified", v));

  // Closure relations from the entity table, when the mesh carries one.
  std::set<std::array<std::int32_t, 4>> bounds;  // (dim, tag, dim-1, tag)
  for (const auto& e : m.entities)
    for (auto b : e.bounding) bounds.insert({e.dim, e.tag, e.dim - 1, b < 0 ? -b : b});
  const bool have_entities = !m.entities.empty();
  auto in_closure = [&](ModelRef low, ModelRef high) {
    if (low.dim > high.dim) return false;
    if (low.dim == high.dim) return low.tag == high.tag;
    if (!have_entities) return true;
    // Walk down one dimension at a time (entity tables are small).
    std::vector<ModelRef> frontier{high};
    while (!frontier.empty() && frontier.front().dim > low.dim) {
      std::vector<ModelRef> next;
      for (const auto& h : frontier)
        for (auto it = bounds.lower_bound({h.dim, h.tag, INT32_MIN, INT32_MIN});
             it != bounds.end() && (*it)[0] == h.dim && (*it)[1] == h.tag; ++it)
          next.push_back({(*it)[2], (*it)[3]});
      std::sort(next.begin(), next.end());
      next.erase(std::unique(next.begin(), next.end()), next.end());
      frontier = std::move(next);
    }
    return std::find(frontier.begin(), frontier.end(), low) != frontier.end();
  };

  // Each boundary face must be a classified triangle; each triangle a face.
  std::map<TriKey, std::int32_t> tri_tag;
  for (std::size_t i = 0; i < m.tris.size(); ++i) {
    const auto& tr = m.tris[i];
    if (tr.verts[0] >= nv || tr.verts[1] >= nv || tr.verts[2] >= nv) {
      rep.add(Kind::kTriNotOnMesh, static_cast<std::int64_t>(i), fmt::format("triangle {} references a vertex >= {}", i, nv));
      continue;
    }
    tri_tag[sorted_key(tr.verts[0], tr.verts[1], tr.verts[2])] = tr.face_tag;
  }
  std::set<TriKey> tet_faces;
  for (const auto& [key, packed] : boundary) {
    tet_faces.insert(key);
    if (!tri_tag.count(key))
      rep.add(Kind::kUnclassifiedBoundary, packed,
              fmt::format("boundary face ({}, {}, {}) of tet {} is not classified on a model face", key[0], key[1], key[2], face_tet(packed)));
  }
  for (std::size_t i = 0; i < m.tris.size(); ++i) {
    const auto& tr = m.tris[i];
    if (tr.verts[0] >= nv || tr.verts[1] >= nv || tr.verts[2] >= nv) continue;
    const TriKey key = sorted_key(tr.verts[0], tr.verts[1], tr.verts[2]);
    if (!tet_faces.count(key) && !is_tet_face(m, key))
      rep.add(Kind::kTriNotOnMesh, static_cast<std::int64_t>(i),
              fmt::format("triangle {} ({}, {}, {}) on model face {} is not a boundary face of the tets", i, key[0], key[1], key[2], tr.face_tag));
    const ModelRef face{2, tr.face_tag};
    for (VertId v : tr.verts)
      if (m.vert_class[v].valid() && !in_closure(m.vert_class[v], face))
        rep.add(Kind::kClassification, v,
                fmt::format("vertex {} classified on ({}, {}) lies on triangle {} of model face {} outside its closure", v,
                            m.vert_class[v].dim, m.vert_class[v].tag, i, tr.face_tag));
  }

  // Edges: classified on a model edge, vertices on it or its end points; a
  // boundary triangle's edges lie on its face or the face's closure.
  std::map<std::pair<VertId, VertId>, std::int32_t> edge_tag;
  for (std::size_t i = 0; i < m.edges.size(); ++i) {
    const auto& e = m.edges[i];
    if (e.verts[0] >= nv || e.verts[1] >= nv) {
      rep.add(Kind::kClassification, static_cast<std::int64_t>(i), fmt::format("edge {} references a vertex >= {}", i, nv));
      continue;
    }
    edge_tag[std::minmax(e.verts[0], e.verts[1])] = e.edge_tag;
    const ModelRef curve{1, e.edge_tag};
    for (VertId v : e.verts)
      if (m.vert_class[v].valid() && !in_closure(m.vert_class[v], curve))
        rep.add(Kind::kClassification, v,
                fmt::format("vertex {} classified on ({}, {}) bounds edge {} of model edge {}: the vertex must be on that "
                            "edge or one of its end vertices", v, m.vert_class[v].dim, m.vert_class[v].tag, i, e.edge_tag));
  }
  for (const auto& tr : m.tris) {
    if (tr.verts[0] >= nv || tr.verts[1] >= nv || tr.verts[2] >= nv) continue;
    for (const auto& te : kTriEdges) {
      const auto key = std::minmax(tr.verts[te[0]], tr.verts[te[1]]);
      auto it = edge_tag.find(key);
      if (it != edge_tag.end()) {
        if (!in_closure({1, it->second}, {2, tr.face_tag}))
          rep.add(Kind::kClassification, key.first,
                  fmt::format("edge ({}, {}) on model edge {} bounds a triangle of model face {} that model edge {} does not bound",
                              key.first, key.second, it->second, tr.face_tag, it->second));
      } else {
        // Implicitly on the face: neither end may be interior to the volume.
        for (VertId v : {key.first, key.second})
          if (m.vert_class[v].dim == 3)
            rep.add(Kind::kClassification, v, fmt::format("vertex {} is classified in a region but lies on model face {}", v, tr.face_tag));
      }
    }
  }
  // A vertex classified on a model face, edge or vertex must be on the boundary.
  std::vector<char> on_boundary(nv, 0);
  for (const auto& [key, packed] : boundary)
    for (VertId v : key) on_boundary[v] = 1;
  for (const auto& [key, tag] : tri_tag)
    for (VertId v : key) on_boundary[v] = 1;
  for (VertId v = 0; v < nv; ++v)
    if (m.vert_class[v].dim >= 0 && m.vert_class[v].dim < 3 && !on_boundary[v] && m.vert2tet.size() == nv &&
        m.vert2tet[v] != kNone && !m.tris.empty())
      rep.add(Kind::kClassification, v,
              fmt::format("vertex {} is classified on model entity ({}, {}) but is interior to the mesh", v,
                          m.vert_class[v].dim, m.vert_class[v].tag));
}

}  // namespace

ValidationReport validate(const TetMesh& m, Level level, std::size_t max_issues) {
  ValidationReport report;
  Reporter rep(report, max_issues);
  if (m.tet_region.size() != m.num_tets()) {
    rep.add(Kind::kClassification, -1, "region array has the wrong size");
    return report;
  }
  if (!check_tets(m, rep)) return report;  // later checks index coords by these ids
  check_adjacency(m, rep);
  const auto boundary = check_conformity(m, rep);
  if (level == Level::kFull) check_classification(m, boundary, rep);
  return report;
}

}  // namespace cm::mesh

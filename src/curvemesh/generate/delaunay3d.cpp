#include "curvemesh/generate/delaunay3d.hpp"

#include <algorithm>
#include <stdexcept>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/generate/spatial_sort.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace cm::generate {

int insphere_perturbed(const mesh::TetMesh& m, const std::array<VertId, 4>& t, VertId e) {
  const double* p[5] = {m.coords[t[0]].data(), m.coords[t[1]].data(), m.coords[t[2]].data(),
                        m.coords[t[3]].data(), m.coords[e].data()};
  const int s = predicates::insphere(p[0], p[1], p[2], p[3], p[4]);
  if (s != 0) return s;
  // Lift point i by ε^(rank): the derivative of insphere with respect to the
  // lift of tet vertex k is the sign of the barycentric coordinate of e in
  // the tet (e put in place of vertex k); for e itself it is -1 (lifting e
  // moves it outside). The most perturbed point whose term is nonzero wins.
  std::array<std::pair<VertId, int>, 5> order{{{t[0], 0}, {t[1], 1}, {t[2], 2}, {t[3], 3}, {e, 4}}};
  std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [id, slot] : order) {
    if (slot == 4) return -1;
    const double* q[4] = {p[0], p[1], p[2], p[3]};
    q[slot] = p[4];
    const int o = predicates::orient3d(q[0], q[1], q[2], q[3]);
    if (o != 0) return o;
  }
  return -1;  // unreachable for a positive tet
}

Delaunay3d::Delaunay3d(mesh::TetMesh& m, const Vec3& lo, const Vec3& hi) : editor_(m) {
  const Vec3 c = 0.5 * (lo + hi);
  const double r = std::max(0.5 * (hi - lo).norm(), 1e-300);
  // A regular tet with inradius 10 r: every box point is well inside, and the
  // far vertices stay within the predicates' exact range.
  const double s = 10.0 * r * std::sqrt(3.0);
  const Vec3 dirs[4] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  for (int k = 0; k < 4; ++k) far_[k] = m.add_vert(c + s * dirs[k]);
  m.resize_vertex_arrays();
  m.vert2tet.resize(m.coords.size(), kNone);
  std::array<VertId, 4> t = far_;
  if (predicates::orient3d(m.coords[t[0]].data(), m.coords[t[1]].data(), m.coords[t[2]].data(),
                           m.coords[t[3]].data()) < 0)
    std::swap(t[2], t[3]);
  last_ = editor_.allocate(t, 0);
}

TetId Delaunay3d::locate(const Vec3& x, TetId hint) {
  const auto& m = editor_.mesh();
  TetId t = hint;
  if (t == kNone || t >= m.tet2verts.size() || editor_.is_dead(t)) t = last_;
  if (editor_.is_dead(t)) {
    for (t = 0; editor_.is_dead(t); ++t) {
    }
  }
  int from = -1;  // the face we entered through: x is known to be behind it
  for (std::size_t steps = 0;; ++steps) {
    const auto& tv = m.tet2verts[t];
    rng_ ^= rng_ << 13;
    rng_ ^= rng_ >> 7;
    rng_ ^= rng_ << 17;
    const int start = static_cast<int>(rng_ & 3u);
    int exit = -1;
    for (int k = 0; k < 4; ++k) {
      const int f = (start + k) & 3;
      if (f == from) continue;
      const auto& fv = mesh::kFaceVerts[f];
      if (predicates::orient3d(m.coords[tv[fv[0]]].data(), m.coords[tv[fv[1]]].data(), m.coords[tv[fv[2]]].data(),
                               x.data()) > 0) {
        exit = f;
        break;
      }
    }
    if (exit < 0) {
      walk_steps_ += steps;
      return t;
    }
    const Index across = m.tet2adj[4 * t + exit];
    if (across == kNone) throw std::domain_error("Delaunay3d: point outside the enclosing tetrahedron");
    t = mesh::face_tet(across);
    from = mesh::face_index(across);
  }
}

Index Delaunay3d::find_face(const std::array<VertId, 3>& face) const {
  const auto& m = editor_.mesh();
  if (face[0] >= m.vert2tet.size() || m.vert2tet[face[0]] == kNone) return kNone;
  mesh::collect_ball(m, face[0], ball_);
  for (TetId t : ball_) {
    const int i1 = mesh::local_index(m, t, face[1]), i2 = mesh::local_index(m, t, face[2]);
    if (i1 < 0 || i2 < 0) continue;
    const int i0 = mesh::local_index(m, t, face[0]);
    return mesh::pack_face(t, 6 - i0 - i1 - i2);  // the local face opposite the fourth vertex
  }
  return kNone;
}

bool Delaunay3d::protect(const std::array<VertId, 3>& face) {
  const Index f = find_face(face);
  if (f == kNone) return false;
  if (!editor_.face_marked(f)) ++protected_count_;
  editor_.mark_face(f);
  return true;
}

bool Delaunay3d::is_protected(const std::array<VertId, 3>& face) const {
  const Index f = find_face(face);
  return f != kNone && editor_.face_marked(f);
}

Delaunay3d::Result Delaunay3d::insert(VertId v, TetId hint) {
  auto& m = editor_.mesh();
  if (m.vert2tet.size() < m.coords.size()) m.vert2tet.resize(m.coords.size(), kNone);
  Result res;
  const Vec3 x = m.coords[v];
  const TetId t0 = locate(x, hint);
  for (VertId w : m.tet2verts[t0])
    if (m.coords[w] == x) {
      res.refusal = modify::Refusal::kDuplicatePoint;
      res.duplicate_of = w;
      return res;
    }
  cavity_.reset(editor_);
  cavity_.add(editor_, t0);
  stack_.assign(1, t0);
  const bool constrained = protected_count_ != 0;
  while (!stack_.empty()) {
    const TetId t = stack_.back();
    stack_.pop_back();
    for (int f = 0; f < 4; ++f) {
      const Index across = m.tet2adj[4 * t + f];
      if (across == kNone) continue;
      const TetId n = mesh::face_tet(across);
      if (cavity_.contains(editor_, n)) continue;
      if (constrained && editor_.face_marked(mesh::pack_face(t, f))) continue;
      if (insphere_perturbed(m, m.tet2verts[n], v) > 0) {
        cavity_.add(editor_, n);
        stack_.push_back(n);
      }
    }
  }
  cavity_.compute_boundary(editor_);
  res.cavity_size = cavity_.tets().size();
  if (const auto r = modify::check_star(m, cavity_, v); r != modify::Refusal::kNone) {
    // Unconstrained cavities are star-shaped by construction (see header).
    if (!constrained) throw std::logic_error("Delaunay3d: unconstrained cavity not star-shaped");
    res.refusal = r;
    return res;
  }
  const auto created = modify::fill_star(editor_, cavity_, v);
  last_ = created.front();
  return res;
}

std::vector<VertId> Delaunay3d::insert_all(std::span<const VertId> verts) {
  const auto& m = editor_.mesh();
  std::vector<Vec3> pts(verts.size());
  for (std::size_t i = 0; i < verts.size(); ++i) pts[i] = m.coords[verts[i]];
  std::vector<VertId> dup(verts.size(), kNone);
  for (std::uint32_t i : brio_order(pts)) {
    const Result r = insert(verts[i]);
    if (r.refusal == modify::Refusal::kDuplicatePoint) dup[i] = r.duplicate_of;
  }
  return dup;
}

}  // namespace cm::generate

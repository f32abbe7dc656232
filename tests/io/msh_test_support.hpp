#pragma once
// Helpers shared by the MSH tests: a temporary directory, reading a file, and
// the exact comparison of two meshes on everything MSH files carry.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <vector>

#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::io::msh_test {

namespace fs = std::filesystem;
using mesh::ModelRef;
using mesh::Param;
using mesh::TetMesh;

class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "cm_test_msh_XXXXXX").string();
    path_ = mkdtemp(pattern.data());
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

inline TetMesh read_path(const std::string& path) { return read_msh(read_file_bytes(path), path); }

inline bool same_param(const Param& a, const Param& b) {
  const auto eq = [](double x, double y) { return (std::isnan(x) && std::isnan(y)) || x == y; };
  return eq(a.u, b.u) && eq(a.v, b.v);
}

inline std::vector<std::tuple<int, int, std::vector<int>, std::vector<int>>> sorted_entities(
    const TetMesh& m) {
  std::vector<std::tuple<int, int, std::vector<int>, std::vector<int>>> out;
  for (const auto& e : m.entities) out.emplace_back(e.dim, e.tag, e.bounding, e.physicals);
  std::sort(out.begin(), out.end());
  return out;
}

// What same_mesh compares besides coordinates and elements.
struct Compare {
  bool entities = true;
  bool classification = true;  ///< vert_class and vert_param
  double tol = 0;              ///< > 0: coordinates up to tol (gmsh's 16-digit text)
};

// Exact equality of everything the MSH formats carry (up to `how`).
inline ::testing::AssertionResult same_mesh(const TetMesh& a, const TetMesh& b, Compare how = {}) {
  const double tol = how.tol;
  const auto close = [&](const Vec3& x, const Vec3& y) {
    return tol == 0 ? x == y : (x - y).norm() <= tol;
  };
  if (a.num_verts() != b.num_verts())
    return ::testing::AssertionFailure()
           << "vertex counts " << a.num_verts() << " vs " << b.num_verts();
  for (VertId v = 0; v < a.num_verts(); ++v) {
    if (!close(a.coords[v], b.coords[v]))
      return ::testing::AssertionFailure() << "coords of vertex " << v;
    if (!how.classification) continue;
    if (a.vert_class[v] != b.vert_class[v])
      return ::testing::AssertionFailure() << "class of vertex " << v;
    if (!same_param(a.vert_param[v], b.vert_param[v]))
      return ::testing::AssertionFailure() << "param of vertex " << v;
  }
  if (a.tet2verts != b.tet2verts || a.tet_region != b.tet_region)
    return ::testing::AssertionFailure() << "tets differ";
  if (a.tris.size() != b.tris.size())
    return ::testing::AssertionFailure() << "triangle counts differ";
  for (std::size_t i = 0; i < a.tris.size(); ++i)
    if (a.tris[i].verts != b.tris[i].verts || a.tris[i].face_tag != b.tris[i].face_tag)
      return ::testing::AssertionFailure() << "triangle " << i;
  if (a.edges.size() != b.edges.size())
    return ::testing::AssertionFailure() << "edge counts differ";
  for (std::size_t i = 0; i < a.edges.size(); ++i)
    if (a.edges[i].verts != b.edges[i].verts || a.edges[i].edge_tag != b.edges[i].edge_tag)
      return ::testing::AssertionFailure() << "edge " << i;
  if (a.high_order.order() != b.high_order.order())
    return ::testing::AssertionFailure() << "orders differ";
  for (TetId t = 0; t < a.num_tets(); ++t) {
    const auto na = mesh::gather_tet_nodes(a, t), nb = mesh::gather_tet_nodes(b, t);
    for (std::size_t k = 0; k < na.size(); ++k)
      if (!close(na[k], nb[k]))
        return ::testing::AssertionFailure() << "node " << k << " of tet " << t;
  }
  for (const auto& tri : a.tris)
    if (mesh::gather_tri_nodes(a, tri.verts) != mesh::gather_tri_nodes(b, tri.verts) && tol == 0)
      return ::testing::AssertionFailure() << "triangle nodes differ";
  if (how.entities && sorted_entities(a) != sorted_entities(b))
    return ::testing::AssertionFailure() << "entities differ";
  return ::testing::AssertionSuccess();
}

inline TetMesh round_trip(const TetMesh& m, bool binary, const TempDir& dir) {
  const std::string path = dir.file(binary ? "rt_bin.msh" : "rt_ascii.msh");
  write_msh41(m, path, binary);
  return read_path(path);
}

inline const mesh::EntityInfo* find_entity(const TetMesh& m, int dim, int tag) {
  for (const auto& e : m.entities)
    if (e.dim == dim && e.tag == tag) return &e;
  return nullptr;
}

}  // namespace cm::io::msh_test

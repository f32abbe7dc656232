#pragma once
// Meshes to curve in the curved-module tests: the project's own volume
// mesher on built-in shapes and shared models. `alpha` sets how coarse the
// curvature sizing is: 0.25 leaves edges spanning up to ~90° of a small
// hole, where curving makes many tets invalid (what the repair is for).
#include <algorithm>
#include <memory>
#include <set>
#include <string>

#include "curvemesh/curved/curve.hpp"
#include "curvemesh/generate/volume_mesh.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/optimize/improve.hpp"
#include "curvemesh/size/build.hpp"

namespace cm::test {

struct Meshed {
  std::unique_ptr<geom::Model> model;
  mesh::TetMesh m;
};

inline std::string model_path(const std::string& spec) {
  return spec.rfind("builtin:", 0) == 0 ? spec : std::string(CM_SHARED_DIR) + "/models/" + spec;
}

/// As `curvemesh mesh MODEL --curv-alpha alpha` does: mesh, then optimize
/// with boundary vertices on the model.
inline Meshed mesh_for_curving(const std::string& spec, double alpha, double hmax = 0) {
  Meshed r;
  r.model = geom_occ::load_model(model_path(spec));
  size::SizeOptions so;
  so.curvature = size::CurvatureRule::relative_deviation(alpha);
  so.hmax = hmax;
  const auto sf = size::build_size_field(*r.model, so);
  r.m = generate::mesh_volume(*r.model, *sf.field);
  optimize::ImproveOptions io;
  io.model = r.model.get();
  optimize::improve_quality(r.m, io);
  return r;
}

/// Boundary edges of m (edges of its triangles and its classified edges),
/// each as (smaller id, larger id).
inline std::set<std::pair<VertId, VertId>> boundary_edges(const mesh::TetMesh& m) {
  std::set<std::pair<VertId, VertId>> out;
  auto add = [&](VertId a, VertId b) { out.insert({std::min(a, b), std::max(a, b)}); };
  for (const auto& t : m.tris)
    for (const auto& e : mesh::kTriEdges) add(t.verts[e[0]], t.verts[e[1]]);
  for (const auto& e : m.edges) add(e.verts[0], e.verts[1]);
  return out;
}

}  // namespace cm::test

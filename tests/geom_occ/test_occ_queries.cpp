// Point queries on every shared model: closest point (10 000 face probes and
// 2 000 edge probes per model, a few hundred against BRepExtrema), the
// trimmed-face test against BRepClass_FaceClassifier, p-curves against the
// edges, normals against the solid, and bitwise determinism across threads.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepClass3d_SolidClassifier.hxx>
#include <BRepClass_FaceClassifier.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRep_Tool.hxx>
#include <TopoDS.hxx>
#include <gp_Pnt.hxx>

#include "curvemesh/geom_occ/detail/occ_model.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "occ_reference.hpp"

namespace cm::geom_occ {
namespace {

using geom::EntityRef;

class ModelQueries : public ::testing::TestWithParam<std::string> {};

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = test::base_name(info.param);
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

gp_Pnt to_gp(const Vec3& p) { return gp_Pnt(p.x(), p.y(), p.z()); }

struct Probe {
  EntityRef entity;
  Vec3 x;
  Vec3 source;           // a point of the entity the probe was made from
  bool source_on_entity;  // whether `source` is inside the trimmed face
};

// Probes around a subset of faces (every face when there are few): a point
// of the face's UV box, pushed off in a random direction by up to a fifth of
// the face's size.
std::vector<Probe> face_probes(const geom::Model& m, int count, std::mt19937& rng) {
  const int nfaces = m.count(2);
  const int stride = std::max(1, nfaces / 24);
  std::vector<int> faces;
  for (int f = 1; f <= nfaces; f += stride) faces.push_back(f);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> gauss;
  std::vector<Probe> probes;
  for (int i = 0; i < count; ++i) {
    const int f = faces[i % faces.size()];
    const geom::ParamRange r = m.param_range({2, f});
    const Vec2 uv(r.u0 + unit(rng) * (r.u1 - r.u0), r.v0 + unit(rng) * (r.v1 - r.v0));
    const Vec3 p = m.face_point(f, uv);
    const Vec3 dir = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    const double size = m.bounding_box({2, f}).diagonal();
    probes.push_back({{2, f}, p + dir * (0.2 * size * unit(rng)), p, m.contains_param(f, uv)});
  }
  return probes;
}

std::vector<Probe> edge_probes(const geom::Model& m, int count, std::mt19937& rng) {
  std::vector<int> edges;
  for (int e = 1; e <= m.count(1); ++e)
    if (!m.is_degenerate(e)) edges.push_back(e);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> gauss;
  std::vector<Probe> probes;
  for (int i = 0; i < count; ++i) {
    const int e = edges[(i * 7919) % edges.size()];
    const geom::ParamRange r = m.param_range({1, e});
    const Vec3 p = m.edge_point(e, r.u0 + unit(rng) * (r.u1 - r.u0));
    const Vec3 dir = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    const double size = m.bounding_box({1, e}).diagonal();
    probes.push_back({{1, e}, p + dir * (0.3 * size * unit(rng)), p, true});
  }
  return probes;
}

// How far a point can be from an entity and still count as on it: its
// tolerance and, for a face, its boundary edges' (whose 3D curves and
// p-curves disagree by up to that much).
double on_tolerance(const geom::Model& m, const EntityRef& e) {
  double tol = std::max(m.tolerance(e), 1e-7 * m.bounding_box().diagonal());
  if (e.dim == 2) {
    for (const geom::Loop& loop : m.face_loops(e.tag))
      for (const geom::OrientedUse& use : loop.edges) tol = std::max(tol, m.tolerance({1, use.tag}));
  }
  return tol;
}

bool same_bits(const geom::Projection& a, const geom::Projection& b) {
  return std::memcmp(a.point.data(), b.point.data(), sizeof(double) * 3) == 0 &&
         std::memcmp(a.param.data(), b.param.data(), sizeof(double) * 2) == 0 &&
         std::memcmp(&a.distance, &b.distance, sizeof(double)) == 0;
}

TEST_P(ModelQueries, ClosestPointIsOnTheEntityAndNoFartherThanKnownPoints) {
  const std::string path = GetParam();
  const auto model = load_model(path);
  const double scale = model->bounding_box().diagonal();
  const double eps = 1e-9 * scale;
  std::mt19937 rng(12345);
  std::vector<Probe> probes = face_probes(*model, 10000, rng);
  const std::vector<Probe> on_edges = edge_probes(*model, 2000, rng);
  probes.insert(probes.end(), on_edges.begin(), on_edges.end());

  const auto boundary_tolerance = [&](const EntityRef& e) { return on_tolerance(*model, e); };
  std::vector<geom::Projection> serial(probes.size());
  int off_entity = 0, farther = 0, outside = 0, hint_changed = 0;
  for (std::size_t i = 0; i < probes.size(); ++i) {
    const Probe& p = probes[i];
    const geom::Projection res = serial[i] = model->closest_point(p.entity, p.x);
    const Vec3 at = p.entity.dim == 2 ? model->face_point(p.entity.tag, res.param)
                                      : model->edge_point(p.entity.tag, res.param.x());
    if ((at - res.point).norm() > eps || std::abs((res.point - p.x).norm() - res.distance) > eps) {
      if (++off_entity <= 5)
        ADD_FAILURE() << "probe " << i << " entity " << p.entity.tag << ": returned point is not "
                      << "the entity at the returned parameters";
    }
    if (p.entity.dim == 2 && !model->contains_param(p.entity.tag, res.param)) {
      if (++outside <= 5)
        ADD_FAILURE() << "probe " << i << " face " << p.entity.tag << ": (" << res.param.x()
                      << ", " << res.param.y() << ") is outside the trimmed face";
    }
    // The known point may lie in the boundary's tolerance band, just off
    // the face.
    if (p.source_on_entity &&
        res.distance > (p.x - p.source).norm() + (p.entity.dim == 2 ? boundary_tolerance(p.entity) : eps)) {
      if (++farther <= 5)
        ADD_FAILURE() << "probe " << i << " entity (" << p.entity.dim << ", " << p.entity.tag
                      << "): distance " << res.distance << " > " << (p.x - p.source).norm()
                      << " to a known point of the entity";
    }
    if (i % 10 == 0) {
      const geom::Projection again = model->closest_point(p.entity, p.x, res.param);
      if (again.distance > res.distance + eps) ++hint_changed;
    }
  }
  EXPECT_EQ(off_entity, 0);
  EXPECT_EQ(outside, 0);
  EXPECT_EQ(farther, 0);
  EXPECT_EQ(hint_changed, 0) << "starting from the answer must not give a worse answer";

  // The same queries on 3 threads, each a strided share: bitwise equal.
  std::vector<geom::Projection> threaded(probes.size());
  std::vector<std::thread> threads;
  constexpr int kThreads = 3;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (std::size_t i = t; i < probes.size(); i += kThreads)
        threaded[i] = model->closest_point(probes[i].entity, probes[i].x);
    });
  }
  for (std::thread& t : threads) t.join();
  int differ = 0;
  for (std::size_t i = 0; i < probes.size(); ++i) differ += !same_bits(serial[i], threaded[i]);
  EXPECT_EQ(differ, 0) << "threaded closest points differ from serial ones";

  // A few hundred against BRepExtrema on the independently read face (mm).
  const test::Reference ref = test::read_reference(path);
  const double f = test::mm_per_unit(model->units());
  int mismatched = 0, compared = 0;
  for (std::size_t i = 0; i < probes.size() && compared < 300; i += 37) {
    const Probe& p = probes[i];
    const TopoDS_Shape& shape =
        p.entity.dim == 2 ? ref.faces(p.entity.tag) : ref.edges(p.entity.tag);
    BRepExtrema_DistShapeShape dist(BRepBuilderAPI_MakeVertex(to_gp(p.x * f)).Vertex(), shape);
    if (!dist.IsDone()) continue;
    ++compared;
    const double expected = dist.Value() / f;
    // The model clamps to the boundary as the surface's p-curves draw it,
    // BRepExtrema to the 3D edges: they may differ by the edges' tolerance.
    const double tol = boundary_tolerance(p.entity);
    if (std::abs(serial[i].distance - expected) > tol) {
      if (++mismatched <= 5)
        ADD_FAILURE() << "probe " << i << " entity (" << p.entity.dim << ", " << p.entity.tag
                      << "): distance " << serial[i].distance << ", BRepExtrema " << expected;
    }
  }
  EXPECT_GE(compared, 250);
  EXPECT_EQ(mismatched, 0);
}

TEST_P(ModelQueries, TrimmedFaceTestPCurvesAndNormalsAgreeWithOcc) {
  const std::string path = GetParam();
  const auto model = load_model(path);
  const test::Reference ref = test::read_reference(path);
  const double f = test::mm_per_unit(model->units());
  const double scale = model->bounding_box().diagonal();
  std::mt19937 rng(777);
  std::uniform_real_distribution<double> unit(0, 1);
  int unexplained = 0, classified = 0, pcurve_gaps = 0, wrong_side = 0, sided = 0, loop_sense = 0;
  // About 600 classifications per model: the reference classifier projects
  // each 3D point on the face, which is slow on B-spline faces.
  const int samples_per_face = std::clamp(600 / model->count(2), 2, 30);
  // Normals against the solid classifier on about 40 faces.
  const int sided_stride = std::max(1, model->count(2) / 40);
  // One classifier per region: building one is costly (it indexes the solid).
  std::vector<std::unique_ptr<BRepClass3d_SolidClassifier>> solids;
  for (int region = 1; region <= model->count(3); ++region)
    solids.push_back(std::make_unique<BRepClass3d_SolidClassifier>(ref.solids_map(region)));
  for (int face = 1; face <= model->count(2); ++face) {
    const TopoDS_Face& ref_face = TopoDS::Face(ref.faces(face));
    const geom::ParamRange r = model->param_range({2, face});
    const double face_size = model->bounding_box({2, face}).diagonal();
    // contains_param against the 3D classifier (parametrization-free, so it
    // also holds for files the reference translated to mm).
    for (int i = 0; i < samples_per_face; ++i) {
      const Vec2 uv(r.u0 + unit(rng) * (r.u1 - r.u0), r.v0 + unit(rng) * (r.v1 - r.v0));
      const gp_Pnt p = to_gp(model->face_point(face, uv) * f);
      const bool ours = model->contains_param(face, uv);
      const TopAbs_State theirs = BRepClass_FaceClassifier(ref_face, p, 1e-7 * scale * f).State();
      ++classified;
      if (ours == (theirs != TopAbs_OUT)) continue;
      // Only within the boundary's tolerance may two classifiers differ.
      const double wide = 1.5 * std::max(1e-4 * face_size, on_tolerance(*model, {2, face})) * f;
      if (BRepClass_FaceClassifier(ref_face, p, wide).State() != TopAbs_ON) {
        if (++unexplained <= 5)
          ADD_FAILURE() << "face " << face << " (" << uv.x() << ", " << uv.y() << "): ours "
                        << ours << ", BRepClass_FaceClassifier " << theirs;
      }
    }
    // p-curves: the face at the p-curve point is the edge point.
    double signed_area = 0;
    for (const geom::Loop& loop : model->face_loops(face)) {
      std::vector<Vec2> polygon;
      for (const geom::OrientedUse& use : loop.edges) {
        const geom::ParamRange er = model->param_range({1, use.tag});
        const double tol = std::max(model->tolerance({1, use.tag}), model->tolerance({2, face}));
        constexpr int kSteps = 8;
        for (int k = 0; k < kSteps; ++k) {
          const double s = (use.forward ? k : kSteps - k) / double(kSteps);
          const double t = er.u0 + s * (er.u1 - er.u0);
          const Vec2 uv = model->edge_param_on_face(use.tag, face, t, use.forward);
          polygon.push_back(uv);
          if ((model->face_point(face, uv) - model->edge_point(use.tag, t)).norm() >
              1.5 * tol + 1e-9 * scale) {
            if (++pcurve_gaps <= 5)
              ADD_FAILURE() << "face " << face << " edge " << use.tag << " at " << t
                            << ": p-curve point off the edge";
          }
        }
      }
      double area = 0;
      for (std::size_t k = 0; k < polygon.size(); ++k) {
        const Vec2& a = polygon[k];
        const Vec2& b = polygon[(k + 1) % polygon.size()];
        area += a.x() * b.y() - a.y() * b.x();
      }
      signed_area += loop.outer ? area : 0;
    }
    // The outer loop runs counter-clockwise about the face normal: in (u, v)
    // counter-clockwise when the normal is du x dv, clockwise otherwise.
    const auto random_inside = [&] {
      Vec2 uv;
      do {
        uv = Vec2(r.u0 + unit(rng) * (r.u1 - r.u0), r.v0 + unit(rng) * (r.v1 - r.v0));
      } while (!model->contains_param(face, uv));
      return uv;
    };
    const Vec2 inside = random_inside();
    const geom::SurfaceDerivatives d = model->face_derivatives(face, inside);
    const bool natural = model->face_normal(face, inside).dot(d.du.cross(d.dv)) > 0;
    if ((signed_area > 0) != natural) {
      if (++loop_sense <= 5) ADD_FAILURE() << "face " << face << ": outer loop runs backwards";
    }
    // The normal points out of the face's first region: stepping a little
    // along it leaves the solid, stepping back enters it. Near an edge of a
    // thin face a step can cross another face, so three points vote.
    if ((face - 1) % sided_stride != 0) continue;
    const int region = model->upward({2, face}).front();
    BRepClass3d_SolidClassifier& solid = *solids[region - 1];
    const double step = 1e-4 * scale;
    int right = 0, reversed = 0;
    for (int k = 0; k < 3; ++k) {
      const Vec2 uv = random_inside();
      const Vec3 p = model->face_point(face, uv), n = model->face_normal(face, uv);
      solid.Perform(to_gp((p + step * n) * f), 1e-7 * scale * f);
      const TopAbs_State ahead = solid.State();
      solid.Perform(to_gp((p - step * n) * f), 1e-7 * scale * f);
      const TopAbs_State behind = solid.State();
      right += ahead == TopAbs_OUT && behind == TopAbs_IN;
      reversed += ahead == TopAbs_IN && behind == TopAbs_OUT;
    }
    ++sided;
    if (reversed > right) {
      if (++wrong_side <= 5)
        ADD_FAILURE() << "face " << face << ": normal does not point out of region " << region;
    }
  }
  EXPECT_EQ(unexplained, 0) << "of " << classified;
  EXPECT_EQ(pcurve_gaps, 0);
  EXPECT_EQ(loop_sense, 0);
  EXPECT_EQ(wrong_side, 0) << "of " << sided;
}

// contains_param answers from the loops' polygons away from them and asks
// OCC's classifier near them: it must give OCC's answer everywhere, and the
// polygons must serve nearly every face. Points uniformly in each face's
// (u, v) box, and close to its p-curves, where a misread band would show.
TEST_P(ModelQueries, TrimPolygonsGiveTheClassifiersAnswer) {
  const auto loaded = load_model(GetParam());
  const auto* model = dynamic_cast<const detail::OccModel*>(loaded.get());
  ASSERT_NE(model, nullptr);
  const int nf = model->count(2);
  EXPECT_GE(model->faces_with_trim_polygons(), nf * 9 / 10) << "of " << nf << " faces";
  std::mt19937 rng(4242);
  std::uniform_real_distribution<double> unit(0, 1);
  const int per_face = std::clamp(30000 / nf, 40, 2000);
  int differ = 0, checked = 0;
  for (int face = 1; face <= nf; ++face) {
    const geom::ParamRange r = model->param_range({2, face});
    const double extent = std::max(r.u1 - r.u0, r.v1 - r.v0);
    std::vector<Vec2> points;
    for (int i = 0; i < per_face; ++i)
      points.emplace_back(r.u0 + unit(rng) * (r.u1 - r.u0), r.v0 + unit(rng) * (r.v1 - r.v0));
    for (const geom::Loop& loop : model->face_loops(face))
      for (const geom::OrientedUse& use : loop.edges) {
        const geom::ParamRange er = model->param_range({1, use.tag});
        for (int i = 0; i < 20; ++i) {
          const double u = er.u0 + unit(rng) * (er.u1 - er.u0);
          const Vec2 uv = model->edge_param_on_face(use.tag, face, u, use.forward);
          const double off = i == 0 ? 0.0 : extent * std::pow(10.0, -11 + 10 * unit(rng));
          const double angle = 6.283185307179586 * unit(rng);
          points.push_back(uv + off * Vec2(std::cos(angle), std::sin(angle)));
        }
      }
    for (const Vec2& uv : points) {
      ++checked;
      if (model->contains_param(face, uv) == model->contains_param_by_occ(face, uv)) continue;
      if (++differ <= 5) ADD_FAILURE() << "face " << face << " (" << uv.x() << ", " << uv.y() << ")";
    }
  }
  EXPECT_EQ(differ, 0) << "of " << checked;
}

INSTANTIATE_TEST_SUITE_P(Models, ModelQueries, ::testing::ValuesIn(test::model_files()), test_name);

TEST(OccQueries, BuiltinPartQueriesAreThreadDeterministic) {
  // Curvature, normals and the trimmed-face test, 10 000 each, serial vs 4 threads.
  const auto m = load_model("builtin:part");
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> unit(0, 1);
  struct Query {
    int face;
    Vec2 uv;
  };
  std::vector<Query> queries;
  for (int i = 0; i < 10000; ++i) {
    const int face = 1 + i % m->count(2);
    const geom::ParamRange r = m->param_range({2, face});
    queries.push_back({face, Vec2(r.u0 + unit(rng) * (r.u1 - r.u0), r.v0 + unit(rng) * (r.v1 - r.v0))});
  }
  struct Answer {
    double values[10];
    bool inside;
  };
  const auto answer = [&](const Query& q) {
    Answer a{};
    const geom::Curvatures k = m->face_curvatures(q.face, q.uv);
    const Vec3 n = m->face_normal(q.face, q.uv);
    const double values[10] = {k.k1, k.k2, k.dir1.x(), k.dir1.y(), k.dir1.z(),
                               k.dir2.x(), k.dir2.y(), n.x(), n.y(), n.z()};
    std::copy(values, values + 10, a.values);
    a.inside = m->contains_param(q.face, q.uv);
    return a;
  };
  std::vector<Answer> serial, threaded(queries.size());
  for (const Query& q : queries) serial.push_back(answer(q));
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (std::size_t i = t; i < queries.size(); i += 4) threaded[i] = answer(queries[i]);
    });
  }
  for (std::thread& t : threads) t.join();
  int differ = 0;
  for (std::size_t i = 0; i < queries.size(); ++i)
    differ += std::memcmp(serial[i].values, threaded[i].values, sizeof(serial[i].values)) != 0 ||
              serial[i].inside != threaded[i].inside;
  EXPECT_EQ(differ, 0);
}

}  // namespace
}  // namespace cm::geom_occ

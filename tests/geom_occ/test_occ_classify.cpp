// classify_point of the OpenCASCADE backend: built-in shapes against their
// closed forms, shared models against their mass properties (the inside
// fraction of uniform samples times the box volume is a Monte Carlo volume),
// against their face normals (a step out of a face leaves the region, a step
// in enters it) and against BRepClass3d_SolidClassifier run directly on an
// independent reading (the fast tiers must never contradict it), two-region
// models, errors and thread determinism.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include <BRepClass3d_SolidClassifier.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Solid.hxx>
#include <gp_Pnt.hxx>

#include "curvemesh/geom_occ/load.hpp"
#include "occ_reference.hpp"

namespace cm::geom_occ {
namespace {

using geom::Containment;

// Signed distance (negative inside) of each built-in with its defaults, or a
// lower bound of |distance| where the exact one is awkward (the cone).
struct BuiltinCase {
  std::string spec;
  std::function<double(const Vec3&)> signed_distance;
};

double box_distance(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  const Vec3 d = (lo - p).cwiseMax(p - hi);
  return std::min(d.maxCoeff(), 0.0) + d.cwiseMax(0.0).norm();
}

double capped_distance(double radial, double z, double h) {
  const double axial = std::max(-z, z - h);
  return std::min(std::max(radial, axial), 0.0) + std::hypot(std::max(radial, 0.0), std::max(axial, 0.0));
}

std::vector<BuiltinCase> builtin_cases() {
  return {
      {"builtin:box:dx=2,dy=1,dz=0.5",
       [](const Vec3& p) { return box_distance(p, Vec3::Zero(), Vec3(2, 1, 0.5)); }},
      {"builtin:sphere:r=1.5", [](const Vec3& p) { return p.norm() - 1.5; }},
      {"builtin:cylinder:r=1,h=2",
       [](const Vec3& p) { return capped_distance(std::hypot(p.x(), p.y()) - 1, p.z(), 2); }},
      {"builtin:torus:R=2,r=0.5",
       [](const Vec3& p) { return std::hypot(std::hypot(p.x(), p.y()) - 2, p.z()) - 0.5; }},
      // Radius 1 at z = 0 down to 0.5 at z = 2: the lateral distance is the
      // radial gap times the cosine of the half-angle.
      {"builtin:cone:r1=1,r2=0.5,h=2",
       [](const Vec3& p) {
         const double slope = (0.5 - 1) / 2;
         const double radial = (std::hypot(p.x(), p.y()) - (1 + slope * p.z())) / std::hypot(1.0, slope);
         return capped_distance(radial, p.z(), 2);
       }},
  };
}

geom::BoundingBox padded(const geom::BoundingBox& b, double fraction) {
  geom::BoundingBox out = b;
  out.min -= fraction * b.size();
  out.max += fraction * b.size();
  return out;
}

Vec3 uniform_in(const geom::BoundingBox& b, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0, 1);
  const double x = unit(rng), y = unit(rng), z = unit(rng);
  return b.min + Vec3(x, y, z).cwiseProduct(b.size());
}

TEST(OccClassify, BuiltinsAgreeWithTheirClosedForms) {
  std::mt19937 rng(21);
  for (const BuiltinCase& c : builtin_cases()) {
    SCOPED_TRACE(c.spec);
    const auto model = load_model(c.spec);
    ASSERT_EQ(model->count(3), 1);
    const geom::BoundingBox box = padded(model->bounding_box(), 0.2);
    const double band = 1e-6 * box.diagonal();
    int inside = 0, checked = 0;
    for (int i = 0; i < 3000; ++i) {
      const Vec3 p = uniform_in(box, rng);
      const double d = c.signed_distance(p);
      if (std::abs(d) < band) continue;
      const Containment got = model->classify_point(1, p);
      EXPECT_EQ(got, d < 0 ? Containment::kInside : Containment::kOutside) << p.transpose() << " d " << d;
      inside += got == Containment::kInside;
      ++checked;
    }
    EXPECT_GT(inside, 100);
    EXPECT_GT(checked, 2900);
  }
}

// Points of a face away from its edges, with the region's outward normal
// there: on every region that uses the face.
struct FacePoint {
  int face = 0;
  Vec3 point, outward;  // outward of the face's first region
};

std::vector<FacePoint> face_points(const geom::Model& m, int per_face, double edge_clearance, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<FacePoint> out;
  const int nfaces = m.count(2);
  const int stride = std::max(1, nfaces / 30);
  for (int f = 1; f <= nfaces; f += stride) {
    const geom::ParamRange r = m.param_range({2, f});
    std::vector<int> edges;
    for (const geom::Loop& loop : m.face_loops(f))
      for (const geom::OrientedUse& use : loop.edges) edges.push_back(use.tag);
    int found = 0;
    for (int attempt = 0; attempt < 40 * per_face && found < per_face; ++attempt) {
      const Vec2 uv(r.u0 + unit(rng) * (r.u1 - r.u0), r.v0 + unit(rng) * (r.v1 - r.v0));
      if (!m.contains_param(f, uv)) continue;
      const Vec3 p = m.face_point(f, uv);
      // Near an edge a step along the normal may slide along the
      // neighbouring face or cross it.
      double to_edge = std::numeric_limits<double>::infinity();
      for (const int e : edges) to_edge = std::min(to_edge, m.closest_point({1, e}, p).distance);
      if (to_edge < edge_clearance) continue;
      out.push_back({f, p, m.face_normal(f, uv)});
      ++found;
    }
  }
  return out;
}

// Whether region r sees the face's stored normal as outward.
bool outward_for(const geom::Model& m, int region, int face) {
  for (const geom::OrientedUse& use : m.region_faces(region))
    if (use.tag == face) return use.forward;
  ADD_FAILURE() << "face " << face << " does not bound region " << region;
  return true;
}

// A step of `step` out of each sampled face leaves every region the face
// bounds (entering the other region of an interface face), a step in enters
// it, and the face point itself is on it.
void expect_normal_steps(const geom::Model& m, double step, int per_face) {
  std::mt19937 rng(33);
  const std::vector<FacePoint> points = face_points(m, per_face, 20 * step, rng);
  ASSERT_GE(points.size(), 10u);
  for (const FacePoint& fp : points) {
    const std::vector<int> regions = m.upward({2, fp.face});
    for (const int r : regions) {
      const Vec3 out = outward_for(m, r, fp.face) ? fp.outward : Vec3(-fp.outward);
      EXPECT_EQ(m.classify_point(r, fp.point), Containment::kOn) << "face " << fp.face << " region " << r;
      EXPECT_EQ(m.classify_point(r, fp.point + step * out), Containment::kOutside)
          << "face " << fp.face << " region " << r << " at " << fp.point.transpose();
      EXPECT_EQ(m.classify_point(r, fp.point - step * out), Containment::kInside)
          << "face " << fp.face << " region " << r << " at " << fp.point.transpose();
    }
  }
}

TEST(OccClassify, BuiltinsStepOutOfAndIntoEveryFace) {
  for (const BuiltinCase& c : builtin_cases()) {
    SCOPED_TRACE(c.spec);
    const auto model = load_model(c.spec);
    expect_normal_steps(*model, 1e-5 * model->bounding_box().diagonal(), 12);
  }
}

// Monte Carlo volume of each region against BRepGProp's (model->volume):
// with N uniform points in the box and inside fraction p, the estimate
// p·V_box has standard deviation V_box·sqrt(p(1−p)/N); allow 4 of them.
void expect_monte_carlo_volumes(const geom::Model& m, int samples) {
  std::mt19937 rng(44);
  const geom::BoundingBox box = m.bounding_box();
  const double box_volume = box.size().prod();
  std::vector<int> inside(static_cast<std::size_t>(m.count(3)) + 1, 0);
  for (int i = 0; i < samples; ++i) {
    const Vec3 p = uniform_in(box, rng);
    int regions_holding = 0;
    for (int r = 1; r <= m.count(3); ++r) {
      const bool in = m.classify_point(r, p) != Containment::kOutside;
      inside[static_cast<std::size_t>(r)] += in;
      regions_holding += in;
    }
    // Regions are disjoint: a point in two of them is on their interface.
    if (regions_holding > 1) {
      for (int r = 1; r <= m.count(3); ++r) EXPECT_NE(m.classify_point(r, p), Containment::kInside) << p.transpose();
    }
  }
  for (int r = 1; r <= m.count(3); ++r) {
    const double fraction = double(inside[static_cast<std::size_t>(r)]) / samples;
    const double sigma = box_volume * std::sqrt(std::max(fraction * (1 - fraction), 1.0 / samples) / samples);
    EXPECT_NEAR(fraction * box_volume, m.volume(r), 4 * sigma) << "region " << r;
  }
}

class SharedModelClassify : public ::testing::TestWithParam<std::string> {};

std::string model_path(const std::string& name) { return std::string(CM_SHARED_DIR) + "/models/" + name; }

TEST_P(SharedModelClassify, InsideFractionMatchesTheVolume) {
  const auto model = load_model(model_path(GetParam()));
  expect_monte_carlo_volumes(*model, 3000);
}

TEST_P(SharedModelClassify, StepsAlongFaceNormalsLeaveAndEnterTheRegion) {
  const auto model = load_model(model_path(GetParam()));
  const double diagonal = model->bounding_box().diagonal();
  double tolerance = 0;
  for (int r = 1; r <= model->count(3); ++r) tolerance = std::max(tolerance, model->tolerance({3, r}));
  // Far above the model tolerance, far below the thinnest wall.
  expect_normal_steps(*model, std::max(1e-5 * diagonal, 20 * tolerance), 3);
}

// Uniform points and points at several distances along face normals (so
// that every tier answers some), against the exact classifier on the
// reference reading's solid with the same tolerance. kOn on either side is
// the tolerance band, where the two may legitimately differ.
TEST_P(SharedModelClassify, NeverContradictsTheExactClassifier) {
  const std::string path = model_path(GetParam());
  const auto model = load_model(path);
  const test::Reference ref = test::read_reference(path);
  ASSERT_EQ(ref.solids_map.Extent(), model->count(3));
  const double to_mm = test::mm_per_unit(model->units());
  const double diagonal = model->bounding_box().diagonal();
  std::mt19937 rng(77);
  std::vector<Vec3> points;
  for (int i = 0; i < 600; ++i) points.push_back(uniform_in(model->bounding_box(), rng));
  for (const FacePoint& fp : face_points(*model, 4, 0, rng))
    for (const double s : {-1e-2, -2e-3, -5e-4, -1e-4, 1e-4, 5e-4, 2e-3, 1e-2}) points.push_back(fp.point + s * diagonal * fp.outward);
  // Around edges, in random directions: where two faces meet (the edge
  // pseudo-normal) or a corner sends the decision to the exact classifier.
  std::normal_distribution<double> gauss;
  const int stride = std::max(1, model->count(1) / 40);
  for (int e = 1; e <= model->count(1); e += stride) {
    if (model->is_degenerate(e)) continue;
    const geom::ParamRange pr = model->param_range({1, e});
    for (const double t : {0.2, 0.5, 0.8})
      for (const double s : {3e-4, 1e-3, 3e-3}) {
        const Vec3 dir = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
        points.push_back(model->edge_point(e, pr.u0 + t * (pr.u1 - pr.u0)) + s * diagonal * dir);
      }
  }
  int compared = 0;
  for (int r = 1; r <= model->count(3); ++r) {
    BRepClass3d_SolidClassifier exact(TopoDS::Solid(ref.solids_map(r)));
    const double tolerance = model->tolerance({3, r});
    for (const Vec3& p : points) {
      const Containment got = model->classify_point(r, p);
      exact.Perform(gp_Pnt(p.x() * to_mm, p.y() * to_mm, p.z() * to_mm), tolerance * to_mm);
      const TopAbs_State want = exact.State();
      if (got == Containment::kOn || want == TopAbs_ON) continue;
      ++compared;
      EXPECT_EQ(got == Containment::kInside, want == TopAbs_IN) << "region " << r << " at " << p.transpose();
    }
  }
  EXPECT_GT(compared, 1000);
}

std::string param_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = info.param.substr(0, info.param.find('.'));
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

// Freeform B-splines, many small features, and two regions sharing faces.
INSTANTIATE_TEST_SUITE_P(Models, SharedModelClassify,
                         ::testing::Values("t20_data.step", "Zylkopf.stp", "ring.brep", "SampleCrankshaft4A.stp"),
                         param_name);

TEST(OccClassify, TwoRegionBuiltinsSplitSpaceBetweenTheirRegions) {
  const auto blocks = load_model("builtin:blocks");
  ASSERT_EQ(blocks->count(3), 2);
  // Which region is the block at x < 1 follows the fuse; find it.
  const int left = blocks->center_of_mass(1).x() < 1 ? 1 : 2, right = 3 - left;
  std::mt19937 rng(55);
  for (int i = 0; i < 500; ++i) {
    const Vec3 p = uniform_in(geom::BoundingBox{Vec3(0.01, 0.01, 0.01), Vec3(1.99, 0.99, 0.99)}, rng);
    if (std::abs(p.x() - 1) < 1e-6) continue;
    EXPECT_EQ(blocks->classify_point(left, p), p.x() < 1 ? Containment::kInside : Containment::kOutside);
    EXPECT_EQ(blocks->classify_point(right, p), p.x() > 1 ? Containment::kInside : Containment::kOutside);
  }
  EXPECT_EQ(blocks->classify_point(left, Vec3(1, 0.5, 0.5)), Containment::kOn);
  EXPECT_EQ(blocks->classify_point(right, Vec3(1, 0.5, 0.5)), Containment::kOn);
  expect_monte_carlo_volumes(*blocks, 2000);

  const auto inclusion = load_model("builtin:inclusion:s=2,r=0.5");
  const int ball = inclusion->volume(1) < inclusion->volume(2) ? 1 : 2, shell = 3 - ball;
  for (int i = 0; i < 500; ++i) {
    const Vec3 p = uniform_in(geom::BoundingBox{Vec3::Constant(-0.99), Vec3::Constant(0.99)}, rng);
    if (std::abs(p.norm() - 0.5) < 1e-6) continue;
    EXPECT_EQ(inclusion->classify_point(ball, p), p.norm() < 0.5 ? Containment::kInside : Containment::kOutside);
    EXPECT_EQ(inclusion->classify_point(shell, p), p.norm() > 0.5 ? Containment::kInside : Containment::kOutside);
  }
  expect_normal_steps(*inclusion, 1e-5, 6);
}

TEST(OccClassify, BadRegionsAndPointsThrow) {
  const auto blocks = load_model("builtin:blocks");
  EXPECT_THROW(blocks->classify_point(0, Vec3::Zero()), std::out_of_range);
  EXPECT_THROW(blocks->classify_point(3, Vec3::Zero()), std::out_of_range);
  EXPECT_THROW(blocks->classify_point(1, Vec3(std::nan(""), 0, 0)), std::invalid_argument);
}

// Classifiers are lent out per caller: threads classifying at once give the
// serial answers, whichever classifier of the pool each call gets.
TEST(OccClassify, ConcurrentCallsGiveTheSerialAnswers) {
  const auto model = load_model(model_path("ring.brep"));
  std::mt19937 rng(66);
  std::vector<Vec3> probes;
  for (int i = 0; i < 1500; ++i) probes.push_back(uniform_in(padded(model->bounding_box(), 0.05), rng));
  const auto run = [&](std::size_t offset) {
    std::vector<Containment> out(probes.size() * 2);
    // Different threads start at different probes, so classifiers see
    // different histories.
    for (std::size_t k = 0; k < probes.size(); ++k) {
      const std::size_t i = (k + offset) % probes.size();
      out[2 * i] = model->classify_point(1, probes[i]);
      out[2 * i + 1] = model->classify_point(2, probes[i]);
    }
    return out;
  };
  const std::vector<Containment> serial = run(0);
  std::vector<std::vector<Containment>> results(4);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < results.size(); ++t) threads.emplace_back([&, t] { results[t] = run(377 * t); });
  for (std::thread& t : threads) t.join();
  for (const auto& r : results) EXPECT_TRUE(r == serial);
}

}  // namespace
}  // namespace cm::geom_occ

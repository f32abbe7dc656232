// The size octree: levels of eq. 4.6, 2:1 balance, gradation between
// neighbouring octants, continuity, and never coarser than a request.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <tbb/task_arena.h>

#include "curvemesh/size/curvature_size.hpp"
#include "curvemesh/size/octree.hpp"

#include <algorithm>
#include <atomic>
#include <limits>
#include <memory>

using namespace cm;
using namespace cm::size;

namespace {

geom::BoundingBox unit_box() {
  geom::BoundingBox b;
  b.add(Vec3(0, 0, 0));
  b.add(Vec3(1, 1, 1));
  return b;
}

Vec3 centre(const SizeOctree::Leaf& l) { return l.lo + Vec3::Constant(0.5 * l.side); }

// The invariants every built octree keeps.
void expect_invariants(const SizeOctree& tree, double hgrad) {
  const auto leaves = tree.leaves();
  const auto pairs = tree.face_neighbours();
  ASSERT_FALSE(pairs.empty());
  double worst = 0;
  for (const auto& [a, b] : pairs) {
    const auto& la = leaves[a];
    const auto& lb = leaves[b];
    EXPECT_LE(std::abs(la.level - lb.level), 1) << "2:1 balance";
    const double dh = std::abs(tree.size(centre(la)) - tree.size(centre(lb)));
    const double bound = (hgrad - 1) * (centre(la) - centre(lb)).norm();
    worst = std::max(worst, dh / bound);
  }
  EXPECT_LE(worst, 1 + 1e-9) << "gradation between neighbouring octants";
  for (const auto& l : leaves) {
    // Graded sizes are resolved by octants at most twice their size.
    if (l.level < tree.options().max_depth) {
      EXPECT_LE(l.side, 2 * l.min_size * (1 + 1e-12));
    }
    EXPECT_GE(l.min_size, tree.options().hmin * (1 - 1e-12));
    EXPECT_LE(l.size, tree.options().hmax * (1 + 1e-12));
  }
}

}  // namespace

TEST(SizeOctree, OneRequestRefinesToItsLevelAndGradesAround) {
  OctreeOptions o;
  o.hmin = 1e-4;
  o.hmax = 0.15;
  o.hgrad = 1.3;
  SizeOctree tree(unit_box(), o);
  const Vec3 p(0.31, 0.42, 0.53);
  tree.insert(p, 0.01, SizeSource::kFaceCurvature);
  tree.build();
  EXPECT_LE(tree.size(p), 0.01 * (1 + 1e-12));
  EXPECT_GE(tree.size(p), 0.01 * (1 - 1e-12)) << "the leaf around p has the requested size at its corners";
  EXPECT_EQ(tree.depth(), octree_level(tree.root_side(), 0.01));
  // Away from p sizes grow at most as fast as hgrad allows, and up to hmax.
  for (const double d : {0.05, 0.1, 0.2, 0.4}) {
    const double h = tree.size(p + Vec3(d, 0, 0) / std::sqrt(1.0));
    EXPECT_LE(h, 0.15 + 1e-12);
    EXPECT_LE(h, 0.01 + 0.3 * d + 1e-9);
    EXPECT_GT(h, 0.01);
  }
  EXPECT_NEAR(tree.size(Vec3(0.99, 0.99, 0.01)), 0.15, 1e-12);
  expect_invariants(tree, 1.3);
}

TEST(SizeOctree, ManyRequestsKeepEveryInvariantAndAreNeverCoarsened) {
  OctreeOptions o;
  o.hmin = 1e-3;
  o.hmax = 0.2;
  o.hgrad = 1.2;
  SizeOctree tree(unit_box(), o);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1), logh(std::log(0.005), std::log(0.3));
  std::vector<std::pair<Vec3, double>> requests;
  for (int i = 0; i < 400; ++i) {
    // A curved sheet of requests plus scattered points.
    const double a = u(rng), b = u(rng);
    const Vec3 x = i % 2 ? Vec3(a, b, 0.5 + 0.2 * std::sin(6 * a) * std::cos(4 * b)) : Vec3(u(rng), u(rng), u(rng));
    const double h = std::exp(logh(rng));
    requests.emplace_back(x, h);
    tree.insert(x, h, SizeSource::kFaceCurvature);
  }
  tree.build();
  for (const auto& [x, h] : requests) EXPECT_LE(tree.size(x), std::max(h, o.hmin) * (1 + 1e-9));
  expect_invariants(tree, 1.2);
}

TEST(SizeOctree, InterpolationIsContinuousAcrossOctantsOfDifferentSizes) {
  OctreeOptions o;
  o.hmin = 1e-3;
  o.hmax = 0.3;
  o.hgrad = 1.5;
  SizeOctree tree(unit_box(), o);
  tree.insert(Vec3(0.2, 0.2, 0.2), 0.004, SizeSource::kEntitySize);
  tree.insert(Vec3(0.7, 0.6, 0.3), 0.02, SizeSource::kEntitySize);
  tree.build();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  const double step = 1e-9;
  double worst = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 x(u(rng), u(rng), u(rng));
    for (int axis = 0; axis < 3; ++axis) {
      const Vec3 y = x + step * Vec3::Unit(axis);
      worst = std::max(worst, std::abs(tree.size(x) - tree.size(y)) / step);
    }
  }
  // A continuous piecewise-trilinear field has a bounded slope: (hgrad−1)
  // along grid lines, a few times more through a 2:1 face.
  EXPECT_LT(worst, 4 * (o.hgrad - 1));
}

TEST(SizeOctree, FieldsRefineWhereTheyAskForLessThanAnOctant) {
  OctreeOptions o;
  o.hmin = 1e-3;
  o.hmax = 0.5;
  o.hgrad = 2;
  SizeOctree tree(unit_box(), o);
  const Vec3 c(0.5, 0.5, 0.5);
  tree.insert_field(std::make_shared<AnalyticSizeField>([&](const Vec3& x) { return 0.01 + 0.5 * (x - c).norm(); }));
  tree.build();
  EXPECT_LE(tree.size(c), 0.01 * (1 + 1e-9));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 x(u(rng), u(rng), u(rng));
    const double want = std::min(0.5, 0.01 + 0.5 * (x - c).norm());
    // Never far above the field, and the cone's convexity bounds the excess.
    EXPECT_LE(tree.size(x), want * 1.25) << x.transpose();
  }
  expect_invariants(tree, 2);
}

TEST(SizeOctree, RejectsBadUse) {
  OctreeOptions o;
  o.hmin = 0.1;
  o.hmax = 0.01;
  EXPECT_THROW(SizeOctree(unit_box(), o), std::invalid_argument);
  o.hmax = 1;
  o.hgrad = 0.5;
  EXPECT_THROW(SizeOctree(unit_box(), o), std::invalid_argument);
  o.hgrad = 1.3;
  EXPECT_THROW(SizeOctree(geom::BoundingBox{}, o), std::invalid_argument);
  SizeOctree tree(unit_box(), o);
  EXPECT_THROW(tree.size(Vec3::Zero()), std::logic_error);
  EXPECT_THROW(tree.insert(Vec3::Zero(), NAN, SizeSource::kField), std::invalid_argument);
  tree.build();
  EXPECT_THROW(tree.insert(Vec3::Zero(), 0.5, SizeSource::kField), std::logic_error);
  // hmax everywhere when nothing asks for less.
  EXPECT_DOUBLE_EQ(tree.size(Vec3(0.3, 0.3, 0.3)), 1.0);
}

namespace {

// A size h inside the ball |x - c| < r and none (+inf) outside; vouches for
// boxes that keep clear of the sphere by `clearance`, as a region field does.
class BallField final : public BoxSizeField {
 public:
  BallField(Vec3 c, double r, double h, double clearance) : c_(c), r_(r), h_(h), clearance_(clearance) {}
  double size(const Vec3& x, const SizeHint& = {}) const override {
    ++calls_;
    return (x - c_).norm() < r_ ? h_ : std::numeric_limits<double>::infinity();
  }
  bool uniform_in(const Vec3& lo, const Vec3& hi) const override {
    const double near = (c_.cwiseMax(lo).cwiseMin(hi) - c_).norm();
    double far = 0;
    for (int k = 0; k < 8; ++k)
      far = std::max(far, (Vec3(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z()) - c_).norm());
    return far < r_ - clearance_ || near > r_ + clearance_;
  }
  std::size_t calls() const { return calls_; }

 private:
  Vec3 c_;
  double r_, h_, clearance_;
  mutable std::atomic<std::size_t> calls_{0};
};

// The same values without the box answers.
class PointwiseField final : public SizeField {
 public:
  explicit PointwiseField(std::shared_ptr<const SizeField> f) : f_(std::move(f)) {}
  double size(const Vec3& x, const SizeHint& hint = {}) const override { return f_->size(x, hint); }

 private:
  std::shared_ptr<const SizeField> f_;
};

void expect_same_leaves(const SizeOctree& a, const SizeOctree& b) {
  const auto la = a.leaves(), lb = b.leaves();
  ASSERT_EQ(la.size(), lb.size());
  for (std::size_t i = 0; i < la.size(); ++i) {
    ASSERT_EQ(la[i].lo, lb[i].lo) << i;
    ASSERT_EQ(la[i].level, lb[i].level) << i;
    ASSERT_EQ(la[i].size, lb[i].size) << i;
    ASSERT_EQ(la[i].min_size, lb[i].min_size) << i;
    ASSERT_EQ(la[i].source, lb[i].source) << i;
  }
}

// Requests, an analytic field and a box-aware field, as build_size_field
// gives them.
std::unique_ptr<SizeOctree> make_mixed_tree(std::shared_ptr<const SizeField> ball) {
  OctreeOptions o;
  o.hmin = 1e-3;
  o.hmax = 0.2;
  o.hgrad = 1.25;
  auto tree = std::make_unique<SizeOctree>(unit_box(), o);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0, 1), logh(std::log(0.01), std::log(0.3));
  for (int i = 0; i < 1000; ++i) {
    const double a = u(rng), b = u(rng);
    tree->insert(Vec3(a, b, 0.2 + 0.1 * std::sin(5 * a)), std::exp(logh(rng)),
                 i % 3 ? SizeSource::kFaceCurvature : SizeSource::kEdgeCurvature);
  }
  tree->insert_field(std::make_shared<AnalyticSizeField>([](const Vec3& x) { return 0.02 + 0.4 * (x - Vec3(0.8, 0.8, 0.8)).norm(); }));
  tree->insert_field(std::move(ball));
  tree->build();
  return tree;
}

}  // namespace

TEST(SizeOctree, SameTreeForOneAndManyThreads) {
  const auto ball = std::make_shared<BallField>(Vec3(0.4, 0.6, 0.6), 0.25, 0.04, 1e-3);
  std::unique_ptr<SizeOctree> one, many;
  tbb::task_arena(1).execute([&] { one = make_mixed_tree(ball); });
  tbb::task_arena(std::max(4, tbb::this_task_arena::max_concurrency())).execute([&] { many = make_mixed_tree(ball); });
  expect_same_leaves(*one, *many);
  EXPECT_GT(one->num_leaves(), 5000u);
  expect_invariants(*one, 1.25);
}

TEST(SizeOctree, BoxAnswersGiveTheTreeOfPointAnswersWithFewerCalls) {
  const auto ball = std::make_shared<BallField>(Vec3(0.5, 0.45, 0.55), 0.3, 0.04, 1e-3);
  const auto with_boxes = make_mixed_tree(ball);
  const std::size_t box_calls = ball->calls();
  const auto ball2 = std::make_shared<BallField>(Vec3(0.5, 0.45, 0.55), 0.3, 0.04, 1e-3);
  const auto pointwise = make_mixed_tree(std::make_shared<PointwiseField>(ball2));
  expect_same_leaves(*with_boxes, *pointwise);
  // Only the octants along the sphere are asked point by point.
  EXPECT_LT(3 * box_calls, ball2->calls());
  // Inside the ball, away from its sphere, the size is the ball's.
  EXPECT_LE(with_boxes->size(Vec3(0.5, 0.45, 0.55)), 0.04 * (1 + 1e-12));
  EXPECT_LE(with_boxes->size(Vec3(0.5, 0.65, 0.55)), 0.04 * (1 + 1e-12));
}

TEST(SizeOctree, FirstInsertedRequestNamesTheSourceOnATie) {
  OctreeOptions o;
  o.hmin = 1e-3;
  o.hmax = 0.3;
  for (const SizeSource first : {SizeSource::kEntitySize, SizeSource::kProximity}) {
    SizeOctree tree(unit_box(), o);
    const SizeSource second = first == SizeSource::kEntitySize ? SizeSource::kProximity : SizeSource::kEntitySize;
    tree.insert(Vec3(0.3, 0.3, 0.3), 0.02, first);
    tree.insert(Vec3(0.3001, 0.3, 0.3), 0.02, second);
    tree.build();
    // Other leaves may reach 0.02 by interpolation at a hanging corner and
    // keep that corner's source; none names the second request.
    int named = 0;
    for (const auto& l : tree.leaves())
      if (l.min_size == 0.02) {
        EXPECT_NE(l.source, second);
        named += l.source == first;
      }
    EXPECT_GT(named, 0);
  }
}

// size(x) starts from a grid of octants, not the root: at every leaf's
// centre it must read that leaf, whose trilinear value there is the mean of
// its corners (Leaf::size). A wrong octant from the grid reads a neighbour's
// corners, clamped to its box.
TEST(SizeOctree, PointQueriesReadTheLeafHoldingThePoint) {
  const auto ball = std::make_shared<BallField>(Vec3(0.4, 0.6, 0.6), 0.25, 0.04, 1e-3);
  const auto tree = make_mixed_tree(ball);
  const auto leaves = tree->leaves();
  ASSERT_GT(leaves.size(), 5000u);
  std::size_t wrong = 0;
  for (const auto& l : leaves)
    if (std::abs(tree->size(centre(l)) - l.size) > 1e-12 * l.size) ++wrong;
  EXPECT_EQ(wrong, 0u);
}

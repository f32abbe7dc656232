#include "curvemesh/size/octree.hpp"

#include "curvemesh/core/error.hpp"
#include "curvemesh/size/detail/octree_lattice.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

namespace cm::size {

namespace {

using detail::kCorner;
using detail::kNone32;

constexpr int kMaxDepth = 20;           // keys pack 21 bits per axis
constexpr int kMaxLevelJump = 3;
// Sizes spread by gradation are resolved by octants up to twice their size:
// a graded field varies slowly, and the trilinear interpolation follows it
// (kGradeSafety in octree_grading.cpp covers what it overshoots). Requests
// themselves get eq. 4.6's level exactly.
constexpr double kResolution = 2;
constexpr double kRefineMargin = 0.75;        // per refinement round: at most 8^3 children at once
// Grading and conformity (octree_grading.cpp) are alternated at most this
// many times.
constexpr int kMaxConformPasses = 64;

std::vector<detail::Midpoint> make_midpoints() {
  std::vector<detail::Midpoint> out;
  for (int x = 0; x <= 2; ++x)
    for (int y = 0; y <= 2; ++y)
      for (int z = 0; z <= 2; ++z) {
        const int ones = (x == 1) + (y == 1) + (z == 1);
        if (ones != 1 && ones != 2) continue;  // corners and the centre are not on the boundary midpoints
        detail::Midpoint m{{x, y, z}, {-1, -1, -1, -1}};
        int n = 0;
        for (int c = 0; c < 8; ++c) {
          const auto& k = kCorner[c];
          const bool on = (x == 1 || 2 * k[0] == x) && (y == 1 || 2 * k[1] == y) && (z == 1 || 2 * k[2] == z);
          if (on) m.corners[n++] = c;
        }
        out.push_back(m);
      }
  return out;
}
std::uint64_t spread_bits(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}
}  // namespace

namespace detail {

const std::vector<Midpoint>& midpoints() {
  static const std::vector<Midpoint> m = make_midpoints();
  return m;
}

std::uint64_t morton(std::uint64_t ix, std::uint64_t iy, std::uint64_t iz) {
  return spread_bits(ix) | spread_bits(iy) << 1 | spread_bits(iz) << 2;
}

}  // namespace detail

using detail::midpoints;
using detail::morton;

// Keys are < 2^63, so all ones marks an empty slot.
constexpr std::uint64_t kEmptyKey = ~std::uint64_t{0};

void SizeOctree::CornerMap::reset(std::size_t expected) {
  std::size_t capacity = 16;
  shift_ = 60;
  while (capacity < 2 * expected) {
    capacity *= 2;
    --shift_;
  }
  keys_.assign(capacity, kEmptyKey);
  ids_.assign(capacity, 0);
}

std::size_t SizeOctree::CornerMap::slot(Key k) const {
  // Fibonacci hashing: the top bits of the product mix every key bit.
  return static_cast<std::size_t>((k * 0x9E3779B97F4A7C15ull) >> shift_);
}

std::uint32_t SizeOctree::CornerMap::insert(Key k, std::uint32_t id) {
  const std::size_t mask = keys_.size() - 1;
  for (std::size_t i = slot(k);; i = (i + 1) & mask) {
    if (keys_[i] == k) return ids_[i];
    if (keys_[i] == kEmptyKey) {
      keys_[i] = k;
      ids_[i] = id;
      return id;
    }
  }
}

std::int64_t SizeOctree::CornerMap::find(Key k) const {
  const std::size_t mask = keys_.size() - 1;
  for (std::size_t i = slot(k);; i = (i + 1) & mask) {
    if (keys_[i] == k) return ids_[i];
    if (keys_[i] == kEmptyKey) return -1;
  }
}

SizeOctree::SizeOctree(const geom::BoundingBox& box, const OctreeOptions& options) : opt_(options) {
  if (!(opt_.hmin > 0) || !(opt_.hmax >= opt_.hmin) || !std::isfinite(opt_.hmax))
    throw std::invalid_argument(fmt::format("size octree: need 0 < hmin <= hmax (got {}, {})", opt_.hmin, opt_.hmax));
  if (!(opt_.hgrad >= 1)) throw std::invalid_argument(fmt::format("size octree: hgrad must be >= 1 (got {})", opt_.hgrad));
  opt_.max_depth = std::clamp(opt_.max_depth, 1, kMaxDepth);
  const Vec3 extent = box.size();
  if (!extent.allFinite() || !(extent.maxCoeff() > 0))
    throw std::invalid_argument("size octree: the bounding box is empty");
  side_ = 1.02 * extent.maxCoeff();
  origin_ = 0.5 * (box.min + box.max) - Vec3::Constant(0.5 * side_);
  octants_.push_back({0, 0, 0, -1, 0, 0});
}

std::array<std::uint32_t, 3> SizeOctree::to_units(const Vec3& x) const {
  const double scale = std::ldexp(1.0, opt_.max_depth) / side_;
  const double top = std::ldexp(1.0, opt_.max_depth) - 1;
  std::array<std::uint32_t, 3> u{};
  for (int a = 0; a < 3; ++a) {
    double t = std::floor((x[a] - origin_[a]) * scale);
    if (!(t >= 0)) t = 0;  // also NaN
    u[a] = static_cast<std::uint32_t>(std::min(t, top));
  }
  return u;
}

Vec3 SizeOctree::to_point(std::uint64_t ix, std::uint64_t iy, std::uint64_t iz) const {
  const double unit = std::ldexp(side_, -opt_.max_depth);
  return origin_ + unit * Vec3(double(ix), double(iy), double(iz));
}

std::uint32_t SizeOctree::descend(std::uint32_t o, std::uint32_t ix, std::uint32_t iy, std::uint32_t iz) const {
  while (octants_[o].first_child >= 0) {
    const int bit = opt_.max_depth - octants_[o].level - 1;
    const std::uint32_t child = ((ix >> bit) & 1u) | (((iy >> bit) & 1u) << 1) | (((iz >> bit) & 1u) << 2);
    o = static_cast<std::uint32_t>(octants_[o].first_child) + child;
  }
  return o;
}

std::uint32_t SizeOctree::find(std::uint32_t ix, std::uint32_t iy, std::uint32_t iz) const {
  return descend(0, ix, iy, iz);
}

std::uint32_t SizeOctree::find_near(std::uint32_t o, std::uint32_t ix, std::uint32_t iy, std::uint32_t iz) const {
  for (;;) {
    const Octant& q = octants_[o];
    const std::uint32_t s = units(q.level);
    if (q.level == 0 || (ix - q.ix < s && iy - q.iy < s && iz - q.iz < s)) break;  // unsigned: below is huge
    o = q.parent;
  }
  return descend(o, ix, iy, iz);
}

void SizeOctree::split(std::uint32_t o) {
  const Octant parent = octants_[o];
  CM_ASSERT(parent.first_child < 0 && parent.level < opt_.max_depth);
  const std::uint32_t half = units(parent.level + 1);
  octants_[o].first_child = static_cast<std::int32_t>(octants_.size());
  for (int c = 0; c < 8; ++c)
    octants_.push_back({parent.ix + kCorner[c][0] * half, parent.iy + kCorner[c][1] * half,
                        parent.iz + kCorner[c][2] * half, -1, static_cast<std::uint8_t>(parent.level + 1), o});
}

void SizeOctree::insert(const Vec3& x, double h, SizeSource source) {
  if (built_) throw std::logic_error("size octree: insert after build()");
  if (!x.allFinite() || std::isnan(h) || !(h > 0))
    throw std::invalid_argument(fmt::format("size octree: bad request h = {} at ({}, {}, {})", h, x.x(), x.y(), x.z()));
  const bool below_hmin = source == SizeSource::kCuspStrip || source == SizeSource::kThinClosedFace;
  const double least = below_hmin && opt_.cusp_min > 0 ? std::min(opt_.cusp_min, opt_.hmin) : opt_.hmin;
  if (h < least) {
    h = least;
    source = SizeSource::kHmin;
  }
  if (h >= opt_.hmax) return;  // the default already
  if (requests_.size() >= kNone32) throw std::length_error("size octree: too many requests");
  const int level = std::min(octree_level(side_, h), opt_.max_depth);
  const auto u = to_units(x);
  std::uint32_t o = find(u[0], u[1], u[2]);
  while (octants_[o].level < level) {
    split(o);
    const int bit = opt_.max_depth - octants_[o].level - 1;
    o = static_cast<std::uint32_t>(octants_[o].first_child) +
        (((u[0] >> bit) & 1u) | (((u[1] >> bit) & 1u) << 1) | (((u[2] >> bit) & 1u) << 2));
  }
  requests_.push_back({x, h, source, level});
}

void SizeOctree::insert(std::span<const SizeSample> samples) {
  for (const SizeSample& s : samples) insert(s.point, s.size, s.source);
}

void SizeOctree::insert_field(std::shared_ptr<const SizeField> field) {
  if (built_) throw std::logic_error("size octree: insert_field after build()");
  if (!field) throw std::invalid_argument("size octree: null field");
  FieldState state;
  state.boxes = dynamic_cast<const BoxSizeField*>(field.get());
  state.field = std::move(field);
  fields_.push_back(std::move(state));
}

// Depth first, children in order: the leaves come out in Morton order.
std::vector<std::uint32_t> SizeOctree::leaf_octants() const {
  std::vector<std::uint32_t> out, stack{0};
  while (!stack.empty()) {
    const std::uint32_t o = stack.back();
    stack.pop_back();
    if (octants_[o].first_child < 0) {
      out.push_back(o);
      continue;
    }
    for (std::uint32_t c = 8; c-- > 0;) stack.push_back(static_cast<std::uint32_t>(octants_[o].first_child) + c);
  }
  return out;
}

// 2:1 across faces, edges and corners: a leaf's 26 neighbouring leaves are at
// most one level coarser. Keeps interpolation smooth and bounds the hanging
// corners to edge midpoints and face centres. `work` holds the leaves made
// since the tree was last balanced: only those can be two levels finer than
// a neighbour (an old leaf next to a new one was next to its old ancestor).
//
// Checked per parent, not per leaf: every neighbour of a child lies in its
// parent P or in one of P's 26 neighbours of P's size, so the children are
// balanced exactly when those 26 octants exist, and 8 siblings cost one
// check instead of 8. Octants are never merged, so a parent once checked
// stays balanced: the flag lasts across rounds.
void SizeOctree::balance(std::vector<std::uint32_t> work) {
  const std::int64_t top = std::int64_t{1} << opt_.max_depth;
  while (!work.empty()) {
    const std::uint32_t leaf = work.back();
    work.pop_back();
    if (octants_[leaf].level < 2) continue;
    const std::uint32_t o = octants_[leaf].parent;
    if (o >= balanced_parent_.size()) balanced_parent_.resize(octants_.size(), 0);
    if (balanced_parent_[o]) continue;
    balanced_parent_[o] = 1;
    const Octant me = octants_[o];
    const std::int64_t s = units(me.level);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          const auto probe = [&](std::int64_t lo, int d) { return d < 0 ? lo - 1 : d > 0 ? lo + s : lo; };
          const std::int64_t px = probe(me.ix, dx), py = probe(me.iy, dy), pz = probe(me.iz, dz);
          if (px < 0 || py < 0 || pz < 0 || px >= top || py >= top || pz >= top) continue;
          std::uint32_t q = o;
          for (;;) {
            q = find_near(q, std::uint32_t(px), std::uint32_t(py), std::uint32_t(pz));
            if (octants_[q].level >= me.level) break;
            split(q);
            const auto first = static_cast<std::uint32_t>(octants_[q].first_child);
            for (std::uint32_t c = 0; c < 8; ++c) work.push_back(first + c);
          }
        }
  }
}

// Returns the leaves it made.
std::vector<std::uint32_t> SizeOctree::refine_to_sizes() {
  std::vector<std::uint32_t> made, stack;
  for (const std::uint32_t l : by_octant_) {
    const Octant o = octants_[leaves_[l]];
    double smallest = opt_.hmax;
    for (const std::uint32_t node : leaf_nodes_[l]) smallest = std::min(smallest, node_value_[node]);
    if (o.level >= std::min(octree_level(side_, kResolution * smallest), opt_.max_depth)) continue;
    // Aim below the bound: the new corners, graded, come out somewhat
    // smaller than interpolated, and a margin saves a whole round for them.
    const int want = std::min({octree_level(side_, kRefineMargin * kResolution * smallest), opt_.max_depth,
                               o.level + kMaxLevelJump});
    // Every descendant down to `want`.
    stack.assign(1, leaves_[l]);
    while (!stack.empty()) {
      const std::uint32_t q = stack.back();
      stack.pop_back();
      if (octants_[q].level >= want) {
        made.push_back(q);
        continue;
      }
      split(q);
      for (std::uint32_t c = 0; c < 8; ++c) stack.push_back(static_cast<std::uint32_t>(octants_[q].first_child) + c);
    }
  }
  std::sort(made.begin(), made.end());
  return made;
}

void SizeOctree::build() {
  if (built_) throw std::logic_error("size octree: build() called twice");
  request_order_.resize(requests_.size());
  for (std::uint32_t i = 0; i < requests_.size(); ++i) {
    const auto u = to_units(requests_[i].x);
    request_order_[i] = {morton(u[0], u[1], u[2]), i};
  }
  std::sort(request_order_.begin(), request_order_.end());
  std::vector<std::uint32_t> fresh = leaf_octants();
  std::sort(fresh.begin(), fresh.end());
  for (rounds_ = 1;; ++rounds_) {
    balance(std::move(fresh));
    std::vector<std::uint32_t> seeds = assign_corners();
    build_incidence();
    std::vector<std::uint32_t> dirty = seeds;
    for (int k = 0; k < kMaxConformPasses && !seeds.empty(); ++k) {
      grade(seeds, dirty);
      seeds = conform(dirty);
      dirty = seeds;
    }
    if (rounds_ >= 4 * opt_.max_depth) break;
    fresh = refine_to_sizes();
    if (fresh.empty()) break;
  }
  build_query_grid();
  built_ = true;
}

void SizeOctree::build_query_grid() {
  // As fine as the tree goes, but with no more cells than about twice the
  // octants, so the grid costs less memory than the tree it indexes.
  grid_level_ = 0;
  const int deepest = depth();
  while (grid_level_ < std::min(deepest, 10) && (std::size_t{8} << (3 * grid_level_)) <= 2 * octants_.size())
    ++grid_level_;
  const std::uint32_t n = std::uint32_t{1} << grid_level_;
  grid_.assign(std::size_t{n} * n * n, 0);
  const int shift = opt_.max_depth - grid_level_;
  std::vector<std::uint32_t> stack{0};
  while (!stack.empty()) {
    const std::uint32_t o = stack.back();
    stack.pop_back();
    const Octant& q = octants_[o];
    if (q.first_child >= 0 && q.level < grid_level_) {
      for (std::uint32_t c = 0; c < 8; ++c) stack.push_back(static_cast<std::uint32_t>(q.first_child) + c);
      continue;
    }
    const std::uint32_t span = std::uint32_t{1} << (grid_level_ - q.level);
    const std::uint32_t x0 = q.ix >> shift, y0 = q.iy >> shift, z0 = q.iz >> shift;
    for (std::uint32_t z = z0; z < z0 + span; ++z)
      for (std::uint32_t y = y0; y < y0 + span; ++y)
        std::fill_n(grid_.begin() + ((std::size_t{z} * n + y) * n + x0), span, o);
  }
}

std::uint32_t SizeOctree::find_leaf_fast(const std::array<std::uint32_t, 3>& u) const {
  const int shift = opt_.max_depth - grid_level_;
  const std::size_t n = std::size_t{1} << grid_level_;
  return descend(grid_[((u[2] >> shift) * n + (u[1] >> shift)) * n + (u[0] >> shift)], u[0], u[1], u[2]);
}

double SizeOctree::size(const Vec3& x, const SizeHint&) const {
  if (!built_) throw std::logic_error("size octree: query before build()");
  const std::uint32_t o = find_leaf_fast(to_units(x));
  const Octant& oct = octants_[o];
  const auto leaf = static_cast<std::size_t>(octant_leaf_[o]);
  const auto& c = leaf_nodes_[leaf];
  const double s = leaf_side_[leaf];
  const Vec3 t = ((x - to_point(oct.ix, oct.iy, oct.iz)) / s).cwiseMax(0.0).cwiseMin(1.0);
  const auto v = [&](int k) { return node_value_[c[k]]; };
  const double x00 = v(0) + t.x() * (v(1) - v(0)), x10 = v(2) + t.x() * (v(3) - v(2));
  const double x01 = v(4) + t.x() * (v(5) - v(4)), x11 = v(6) + t.x() * (v(7) - v(6));
  const double y0 = x00 + t.y() * (x10 - x00), y1 = x01 + t.y() * (x11 - x01);
  return y0 + t.z() * (y1 - y0);
}

std::vector<SizeOctree::Leaf> SizeOctree::leaves() const {
  if (!built_) throw std::logic_error("size octree: leaves() before build()");
  std::vector<Leaf> out(leaves_.size());
  for (std::size_t i = 0; i < leaves_.size(); ++i) {
    const std::uint32_t l = by_octant_[i];
    const Octant& o = octants_[leaves_[l]];
    Leaf& leaf = out[i];
    leaf.lo = to_point(o.ix, o.iy, o.iz);
    leaf.level = o.level;
    leaf.side = std::ldexp(side_, -o.level);
    double sum = 0;
    leaf.min_size = std::numeric_limits<double>::infinity();
    for (const std::uint32_t node : leaf_nodes_[l]) {
      sum += node_value_[node];
      if (node_value_[node] < leaf.min_size) {
        leaf.min_size = node_value_[node];
        leaf.source = node_source_[node];
      }
    }
    leaf.size = sum / 8;
  }
  return out;
}

std::vector<std::array<std::size_t, 2>> SizeOctree::face_neighbours() const {
  if (!built_) throw std::logic_error("size octree: face_neighbours() before build()");
  std::vector<std::array<std::size_t, 2>> out;
  // Indices as leaves() numbers them.
  std::vector<std::size_t> position(leaves_.size());
  for (std::size_t i = 0; i < by_octant_.size(); ++i) position[by_octant_[i]] = i;
  const std::int64_t top = std::int64_t{1} << opt_.max_depth;
  for (std::size_t i = 0; i < leaves_.size(); ++i) {
    const std::size_t l = position[i];
    const Octant& o = octants_[leaves_[i]];
    const std::int64_t s = units(o.level);
    for (int axis = 0; axis < 3; ++axis)
      for (const int dir : {-1, 1}) {
        std::array<std::int64_t, 3> p{o.ix, o.iy, o.iz};
        p[axis] += dir < 0 ? -1 : s;
        if (p[axis] < 0 || p[axis] >= top) continue;
        const std::size_t other = position[static_cast<std::size_t>(
            octant_leaf_[find(std::uint32_t(p[0]), std::uint32_t(p[1]), std::uint32_t(p[2]))])];
        out.push_back({std::min(l, other), std::max(l, other)});
      }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

int SizeOctree::depth() const {
  int d = 0;
  for (const Octant& o : octants_) d = std::max(d, int(o.level));
  return d;
}

}  // namespace cm::size


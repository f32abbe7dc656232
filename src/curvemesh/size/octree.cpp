#include "curvemesh/size/octree.hpp"

#include "curvemesh/core/error.hpp"

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

constexpr int kMaxDepth = 20;           // keys pack 21 bits per axis
constexpr int kMaxLevelJump = 3;
// Sizes spread by gradation are resolved by octants up to twice their size:
// a graded field varies slowly, and the trilinear interpolation follows it
// (kGradeSafety covers what it overshoots). Requests themselves get eq. 4.6's
// level exactly.
constexpr double kResolution = 2;
constexpr double kRefineMargin = 0.75;        // per refinement round: at most 8^3 children at once
constexpr double kRelativeTolerance = 1e-12;
// The corner graph is graded with a slightly smaller slope than hgrad asks:
// trilinear interpolation of a convex field (sizes growing away from a
// source) overshoots inside a larger octant, and between the centres of a
// large and a small neighbour that overshoot adds to the slope.
constexpr double kGradeSafety = 0.85;
// Grading and conformity are alternated until neither moves a size by more
// than this (relative); the last conformity pass is exact either way.
constexpr double kConformTolerance = 1e-7;
constexpr int kMaxConformPasses = 64;
// Distance between corners a and b of a unit cube, indexed by a ^ b: they
// differ in 1, 2 or 3 coordinates, along an edge, a face or the body diagonal.
constexpr std::array<double, 8> kCornerDistance = {0, 1, 1, 1.4142135623730951, 1, 1.4142135623730951,
                                                   1.4142135623730951, 1.7320508075688772};

// Corner b of an octant: bit 0 -> +x, bit 1 -> +y, bit 2 -> +z.
constexpr std::array<std::array<int, 3>, 8> kCorner = {
    {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}}};

// Hanging-corner candidates of an octant in half-side units: the 12 edge
// midpoints with their 2 end corners and the 6 face centres with their 4.
struct Midpoint {
  std::array<int, 3> at;           // 0, 1 or 2 half-sides along each axis
  std::array<int, 4> corners;      // -1 pads the edge case
};
std::vector<Midpoint> make_midpoints() {
  std::vector<Midpoint> out;
  for (int x = 0; x <= 2; ++x)
    for (int y = 0; y <= 2; ++y)
      for (int z = 0; z <= 2; ++z) {
        const int ones = (x == 1) + (y == 1) + (z == 1);
        if (ones != 1 && ones != 2) continue;  // corners and the centre are not on the boundary midpoints
        Midpoint m{{x, y, z}, {-1, -1, -1, -1}};
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
const std::vector<Midpoint>& midpoints() {
  static const std::vector<Midpoint> m = make_midpoints();
  return m;
}

// Position on the Morton (Z-order) curve of a lattice point: the bits of x,
// y and z interleaved, x lowest, so that the children of an octant, numbered
// bx + 2by + 4bz, follow each other along the curve and every octant covers
// one contiguous range of it.
std::uint64_t spread_bits(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}
std::uint64_t morton(std::uint64_t ix, std::uint64_t iy, std::uint64_t iz) {
  return spread_bits(ix) | spread_bits(iy) << 1 | spread_bits(iz) << 2;
}

constexpr std::uint32_t kNone32 = std::numeric_limits<std::uint32_t>::max();

// Open-addressing table of field values by lattice key (FieldState).
constexpr std::uint64_t kNoKey = ~std::uint64_t{0};
std::size_t value_slot(const std::vector<std::uint64_t>& keys, std::uint64_t k) {
  const std::size_t mask = keys.size() - 1;
  for (std::size_t i = static_cast<std::size_t>((k * 0x9E3779B97F4A7C15ull) >> 20) & mask;; i = (i + 1) & mask)
    if (keys[i] == k || keys[i] == kNoKey) return i;
}
void reserve_values(std::vector<std::uint64_t>& keys, std::vector<double>& values, std::size_t count) {
  if (2 * count <= keys.size()) return;
  std::size_t capacity = std::max<std::size_t>(keys.size(), 1024);
  while (2 * count > capacity) capacity *= 2;
  std::vector<std::uint64_t> old_keys(capacity, kNoKey);
  std::vector<double> old_values(capacity);
  old_keys.swap(keys);
  old_values.swap(values);
  for (std::size_t i = 0; i < old_keys.size(); ++i)
    if (old_keys[i] != kNoKey) {
      const std::size_t slot = value_slot(keys, old_keys[i]);
      keys[slot] = old_keys[i];
      values[slot] = old_values[i];
    }
}

// Disjoint sets of leaves whose root is the smallest member, so that which
// leaf stands for a set does not depend on the order sets were joined in.
std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t a) {
  while (parent[a] != a) a = parent[a] = parent[parent[a]];
  return a;
}
void join(std::vector<std::uint32_t>& parent, std::uint32_t a, std::uint32_t b) {
  a = find_root(parent, a);
  b = find_root(parent, b);
  if (a != b) parent[std::max(a, b)] = std::min(a, b);
}

}  // namespace

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
  octants_.push_back({0, 0, 0, -1, 0});
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

std::uint32_t SizeOctree::find(std::uint32_t ix, std::uint32_t iy, std::uint32_t iz) const {
  std::uint32_t o = 0;
  while (octants_[o].first_child >= 0) {
    const int bit = opt_.max_depth - octants_[o].level - 1;
    const std::uint32_t child = ((ix >> bit) & 1u) | (((iy >> bit) & 1u) << 1) | (((iz >> bit) & 1u) << 2);
    o = static_cast<std::uint32_t>(octants_[o].first_child) + child;
  }
  return o;
}

void SizeOctree::split(std::uint32_t o) {
  const Octant parent = octants_[o];
  CM_ASSERT(parent.first_child < 0 && parent.level < opt_.max_depth);
  const std::uint32_t half = units(parent.level + 1);
  octants_[o].first_child = static_cast<std::int32_t>(octants_.size());
  for (int c = 0; c < 8; ++c)
    octants_.push_back({parent.ix + kCorner[c][0] * half, parent.iy + kCorner[c][1] * half,
                        parent.iz + kCorner[c][2] * half, -1, static_cast<std::uint8_t>(parent.level + 1)});
}

void SizeOctree::insert(const Vec3& x, double h, SizeSource source) {
  if (built_) throw std::logic_error("size octree: insert after build()");
  if (!x.allFinite() || std::isnan(h) || !(h > 0))
    throw std::invalid_argument(fmt::format("size octree: bad request h = {} at ({}, {}, {})", h, x.x(), x.y(), x.z()));
  if (h < opt_.hmin) {
    h = opt_.hmin;
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
void SizeOctree::balance(std::vector<std::uint32_t> work) {
  const std::int64_t top = std::int64_t{1} << opt_.max_depth;
  while (!work.empty()) {
    const std::uint32_t o = work.back();
    work.pop_back();
    if (octants_[o].first_child >= 0 || octants_[o].level < 2) continue;
    const Octant me = octants_[o];
    const std::int64_t s = units(me.level);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          const auto probe = [&](std::int64_t lo, int d) { return d < 0 ? lo - 1 : d > 0 ? lo + s : lo; };
          const std::int64_t px = probe(me.ix, dx), py = probe(me.iy, dy), pz = probe(me.iz, dz);
          if (px < 0 || py < 0 || pz < 0 || px >= top || py >= top || pz >= top) continue;
          for (;;) {
            const std::uint32_t q = find(std::uint32_t(px), std::uint32_t(py), std::uint32_t(pz));
            if (octants_[q].level + 1 >= me.level) break;
            split(q);
            const auto first = static_cast<std::uint32_t>(octants_[q].first_child);
            for (std::uint32_t c = 0; c < 8; ++c) work.push_back(first + c);
          }
        }
  }
}

// Returns the corners grading and conformity must start from: every corner
// of a leaf made since the last call, and every corner a source lowered
// below what it carried over.
std::vector<std::uint32_t> SizeOctree::assign_corners() {
  // A corner of a leaf stays a corner of one of its descendants, so every
  // old corner has a new id, and its graded and conformed size still holds.
  const std::vector<std::array<std::uint32_t, 3>> old_units = std::move(node_units_);
  const std::vector<double> old_value = std::move(node_value_);
  const std::vector<SizeSource> old_source = std::move(node_source_);
  leaves_ = leaf_octants();
  by_octant_.resize(leaves_.size());
  std::iota(by_octant_.begin(), by_octant_.end(), 0u);
  std::sort(by_octant_.begin(), by_octant_.end(), [&](std::uint32_t a, std::uint32_t b) { return leaves_[a] < leaves_[b]; });
  octant_leaf_.assign(octants_.size(), -1);
  leaf_nodes_.resize(leaves_.size());
  node_of_.reset(2 * leaves_.size() + 8);  // corners <= 8 per leaf, ~1.2 per leaf in practice
  leaf_side_.resize(leaves_.size());
  node_units_.clear();
  for (std::size_t l = 0; l < leaves_.size(); ++l) {
    const Octant& o = octants_[leaves_[l]];
    octant_leaf_[leaves_[l]] = static_cast<std::int32_t>(l);
    leaf_side_[l] = std::ldexp(side_, -o.level);
    const std::uint32_t s = units(o.level);
    for (int c = 0; c < 8; ++c) {
      const std::uint32_t x = o.ix + kCorner[c][0] * s, y = o.iy + kCorner[c][1] * s, z = o.iz + kCorner[c][2] * s;
      const std::uint32_t id = node_of_.insert(key(x, y, z), std::uint32_t(node_units_.size()));
      if (id == node_units_.size()) node_units_.push_back({x, y, z});
      leaf_nodes_[l][c] = id;
    }
  }
  const std::size_t n = node_units_.size();
  node_value_.assign(n, opt_.hmax);
  node_source_.assign(n, SizeSource::kHmax);
  for (std::size_t i = 0; i < old_units.size(); ++i) {
    const auto& u = old_units[i];
    const std::int64_t id = node_of_.find(key(u[0], u[1], u[2]));
    CM_ASSERT(id >= 0);
    node_value_[static_cast<std::size_t>(id)] = old_value[i];
    node_source_[static_cast<std::size_t>(id)] = old_source[i];
  }
  const std::vector<double> carried = node_value_;
  // Leaves and requests are both in Morton order: one merge finds every
  // request's leaf. Per corner the smallest size wins, and among equal
  // sizes the request inserted first.
  std::vector<std::uint32_t> winner(n, kNone32);
  // A carried size keeps its source on a tie: the request that named it
  // may lie in a neighbouring leaf by now.
  for (std::size_t i = 0; i < n; ++i)
    if (carried[i] < opt_.hmax) winner[i] = 0;
  std::size_t k = 0;
  for (std::size_t l = 0; l < leaves_.size() && k < request_order_.size(); ++l) {
    const Octant& o = octants_[leaves_[l]];
    const Key end = morton(o.ix, o.iy, o.iz) + (Key{1} << (3 * (opt_.max_depth - o.level)));
    double best_h = std::numeric_limits<double>::infinity();
    std::uint32_t best = kNone32;
    for (; k < request_order_.size() && request_order_[k].first < end; ++k) {
      const std::uint32_t i = request_order_[k].second;
      if (requests_[i].h < best_h || (requests_[i].h == best_h && i < best)) {
        best_h = requests_[i].h;
        best = i;
      }
    }
    if (best == kNone32) continue;
    for (const std::uint32_t node : leaf_nodes_[l])
      if (best_h < node_value_[node] || (best_h == node_value_[node] && best < winner[node])) {
        node_value_[node] = best_h;
        node_source_[node] = requests_[best].source;
        winner[node] = best;
      }
  }
  for (FieldState& field : fields_) evaluate_field(field);

  std::vector<char> listed(n, 0);
  std::vector<std::uint32_t> seeds;
  for (std::size_t l = 0; l < leaves_.size(); ++l)
    if (leaves_[l] >= cornered_octants_)
      for (const std::uint32_t node : leaf_nodes_[l])
        if (!listed[node]) {
          listed[node] = 1;
          seeds.push_back(node);
        }
  for (std::uint32_t i = 0; i < n; ++i)
    if (!listed[i] && node_value_[i] < carried[i]) seeds.push_back(i);
  cornered_octants_ = static_cast<std::uint32_t>(octants_.size());
  return seeds;
}

// A field's value at every corner and at every leaf's centre (at the finest
// level: its lowest corner), each lowering the corners of its leaves.
void SizeOctree::evaluate_field(FieldState& st) {
  const std::size_t n = node_units_.size(), nl = leaves_.size();
  constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> at_node(n, kUnknown), at_centre(nl, kUnknown);
  const auto clamped = [&](const Vec3& x) { return std::clamp(st.field->size(x), opt_.hmin, opt_.hmax); };
  const auto centre_units = [&](const Octant& o) {
    const std::uint32_t h = o.level < opt_.max_depth ? units(o.level) / 2 : 0;
    return std::array<std::uint32_t, 3>{o.ix + h, o.iy + h, o.iz + h};
  };
  if (st.boxes) {
    // Leaves the field vouches for, joined through shared corners: one value
    // per joined set, taken at the centre of its first leaf.
    std::vector<char> uniform(nl);
    tbb::parallel_for(std::size_t{0}, nl, [&](std::size_t l) {
      const Octant& o = octants_[leaves_[l]];
      const Vec3 lo = to_point(o.ix, o.iy, o.iz);
      uniform[l] = st.boxes->uniform_in(lo, lo + Vec3::Constant(leaf_side_[l]));
    });
    std::vector<std::uint32_t> set(nl), first_leaf(n, kNone32);
    std::iota(set.begin(), set.end(), 0u);
    for (std::uint32_t l = 0; l < nl; ++l) {
      if (!uniform[l]) continue;
      for (const std::uint32_t node : leaf_nodes_[l]) {
        if (first_leaf[node] == kNone32)
          first_leaf[node] = l;
        else
          join(set, l, first_leaf[node]);
      }
    }
    std::vector<std::uint32_t> roots;
    for (std::uint32_t l = 0; l < nl; ++l)
      if (uniform[l] && find_root(set, l) == l) roots.push_back(l);
    tbb::parallel_for(std::size_t{0}, roots.size(), [&](std::size_t r) {
      const auto c = centre_units(octants_[leaves_[roots[r]]]);
      at_centre[roots[r]] = clamped(to_point(c[0], c[1], c[2]));
    });
    for (std::uint32_t l = 0; l < nl; ++l) {
      if (!uniform[l]) continue;
      const double v = at_centre[find_root(set, l)];
      at_centre[l] = v;
      for (const std::uint32_t node : leaf_nodes_[l]) at_node[node] = v;
    }
  }
  // Every other point: its value from an earlier round, or evaluated now,
  // each distinct point once.
  std::vector<double*> targets;
  std::vector<std::size_t> target_slot;
  reserve_values(st.keys, st.values, st.count + n + nl);
  const auto want = [&](const std::array<std::uint32_t, 3>& u, double* out) {
    const Key k = key(u[0], u[1], u[2]);
    const std::size_t slot = value_slot(st.keys, k);
    if (st.keys[slot] == kNoKey) {
      st.keys[slot] = k;
      st.values[slot] = kUnknown;
      ++st.count;
    }
    targets.push_back(out);
    target_slot.push_back(slot);
  };
  for (std::size_t i = 0; i < n; ++i)
    if (std::isnan(at_node[i])) want(node_units_[i], &at_node[i]);
  for (std::size_t l = 0; l < nl; ++l)
    if (std::isnan(at_centre[l])) want(centre_units(octants_[leaves_[l]]), &at_centre[l]);
  std::vector<std::size_t> fresh;
  for (const std::size_t slot : target_slot)
    if (std::isnan(st.values[slot])) {
      st.values[slot] = 0;  // listed once
      fresh.push_back(slot);
    }
  tbb::parallel_for(std::size_t{0}, fresh.size(), [&](std::size_t i) {
    constexpr Key kMask = (Key{1} << 21) - 1;
    const Key k = st.keys[fresh[i]];
    st.values[fresh[i]] = clamped(to_point(k & kMask, (k >> 21) & kMask, k >> 42));
  });
  for (std::size_t t = 0; t < targets.size(); ++t) *targets[t] = st.values[target_slot[t]];

  const auto lower = [&](std::uint32_t node, double h) {
    if (h < node_value_[node]) {
      node_value_[node] = h;
      node_source_[node] = SizeSource::kField;
    }
  };
  for (std::size_t i = 0; i < n; ++i) lower(std::uint32_t(i), at_node[i]);
  for (std::size_t l = 0; l < nl; ++l)
    for (const std::uint32_t node : leaf_nodes_[l]) lower(node, at_centre[l]);
}

// Node -> incident leaves, corner positions and the hanging corners, once
// per refinement round.
void SizeOctree::build_incidence() {
  const std::size_t n = node_value_.size();
  incident_start_.assign(n + 1, 0);
  for (const auto& corners : leaf_nodes_)
    for (const std::uint32_t v : corners) ++incident_start_[v + 1];
  for (std::size_t i = 0; i < n; ++i) incident_start_[i + 1] += incident_start_[i];
  incident_.resize(incident_start_[n]);
  std::vector<std::uint32_t> fill(incident_start_.begin(), incident_start_.end() - 1);
  for (std::uint32_t l = 0; l < leaf_nodes_.size(); ++l)
    for (std::uint32_t c = 0; c < 8; ++c) incident_[fill[leaf_nodes_[l][c]]++] = 8 * l + c;

  hanging_.clear();
  const auto& mids = midpoints();
  for (std::uint32_t l = 0; l < leaves_.size(); ++l) {
    const Octant& o = octants_[leaves_[l]];
    if (o.level >= opt_.max_depth) continue;
    const std::uint32_t half = units(o.level) / 2;
    for (std::size_t k = 0; k < mids.size(); ++k) {
      const auto& at = mids[k].at;
      const std::int64_t node = node_of_.find(key(o.ix + at[0] * half, o.iy + at[1] * half, o.iz + at[2] * half));
      if (node >= 0) hanging_.push_back({l, static_cast<std::uint32_t>(node), static_cast<std::uint8_t>(k)});
    }
  }
  // Conformity is settled finest first and, within a level, in the order
  // octants were made: lowering one face's corners changes what the next
  // face needs, so this order is part of the result.
  std::sort(hanging_.begin(), hanging_.end(), [&](const Hanging& a, const Hanging& b) {
    const std::uint32_t oa = leaves_[a.leaf], ob = leaves_[b.leaf];
    if (octants_[oa].level != octants_[ob].level) return octants_[oa].level > octants_[ob].level;
    return oa != ob ? oa < ob : a.midpoint < b.midpoint;
  });
  hanging_start_.assign(n + 1, 0);
  const auto each_node = [&](const Hanging& hg, auto&& visit) {
    visit(hg.node);
    for (const int c : mids[hg.midpoint].corners)
      if (c >= 0) visit(leaf_nodes_[hg.leaf][c]);
  };
  for (const Hanging& hg : hanging_) each_node(hg, [&](std::uint32_t v) { ++hanging_start_[v + 1]; });
  for (std::size_t i = 0; i < n; ++i) hanging_start_[i + 1] += hanging_start_[i];
  hanging_of_.resize(hanging_start_[n]);
  fill.assign(hanging_start_.begin(), hanging_start_.end() - 1);
  for (std::uint32_t e = 0; e < hanging_.size(); ++e)
    each_node(hanging_[e], [&](std::uint32_t v) { hanging_of_[fill[v]++] = e; });
  hanging_queued_.assign(hanging_.size(), 0);
}

// Shortest paths from the seeds with their sizes as start distances:
// h(b) = min over a of h(a) + (hgrad−1)|ab|, over corners of a common leaf.
// Appends every corner it lowers to `changed`.
void SizeOctree::grade(std::span<const std::uint32_t> seeds, std::vector<std::uint32_t>& changed) {
  const double rate = kGradeSafety * (opt_.hgrad - 1);
  using Item = std::pair<double, std::uint32_t>;
  std::vector<Item> heap;
  heap.reserve(seeds.size());
  for (const std::uint32_t i : seeds)
    if (node_value_[i] < opt_.hmax) heap.emplace_back(node_value_[i], i);
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue(std::greater<>{}, std::move(heap));
  while (!queue.empty()) {
    const auto [h, a] = queue.top();
    queue.pop();
    if (h > node_value_[a]) continue;
    for (std::uint32_t k = incident_start_[a]; k < incident_start_[a + 1]; ++k) {
      const std::uint32_t leaf = incident_[k] >> 3, ca = incident_[k] & 7u;
      const double step = rate * leaf_side_[leaf];
      const auto& corners = leaf_nodes_[leaf];
      for (std::uint32_t cb = 0; cb < 8; ++cb) {
        if (cb == ca) continue;
        const double cand = h + step * kCornerDistance[ca ^ cb];
        const std::uint32_t b = corners[cb];
        if (cand < node_value_[b] * (1 - kConformTolerance)) {
          node_value_[b] = cand;
          node_source_[b] = SizeSource::kGradation;
          queue.emplace(cand, b);
          changed.push_back(b);
        }
      }
    }
  }
}

// Continuity at hanging corners; returns the corners whose size moved.
// Only the entries of hanging_ that a corner in `dirty` takes part in can
// be out of balance (the others were settled in an earlier pass or round
// and none of their corners changed since), so each sweep is a work list
// over those, visited in hanging_'s order, that grows as a sweep moves
// corners the entries still ahead of it read. A corner moved that an entry
// already behind it reads goes to the next pass, as a full sweep would do.
std::vector<std::uint32_t> SizeOctree::conform(std::span<const std::uint32_t> dirty) {
  std::vector<std::uint32_t> moved;
  const auto& mids = midpoints();
  const auto interpolate = [&](const Hanging& hg) {
    double sum = 0;
    int count = 0;
    for (const int c : mids[hg.midpoint].corners)
      if (c >= 0) {
        sum += node_value_[leaf_nodes_[hg.leaf][c]];
        ++count;
      }
    return sum / count;
  };
  std::vector<std::uint32_t> start;
  const auto enlist_all = [&](std::uint32_t node) {
    for (std::uint32_t k = hanging_start_[node]; k < hanging_start_[node + 1]; ++k) {
      const std::uint32_t e = hanging_of_[k];
      if (!hanging_queued_[e]) {
        hanging_queued_[e] = 1;
        start.push_back(e);
      }
    }
  };
  for (const std::uint32_t node : dirty) enlist_all(node);

  // Finest first: where a hanging corner asks for less than a larger
  // octant interpolates there, lower that octant's corners on the face (or
  // edge) to a common cap t, the least change that makes the interpolation
  // equal to what the corner asks; corners already below t keep their size.
  std::priority_queue<std::uint32_t, std::vector<std::uint32_t>, std::greater<>> ahead(std::greater<>{}, start);
  std::vector<std::uint32_t> lowered;
  while (!ahead.empty()) {
    const std::uint32_t e = ahead.top();
    ahead.pop();
    hanging_queued_[e] = 0;
    const Hanging& hg = hanging_[e];
    const double want = node_value_[hg.node];
    if (!(interpolate(hg) - want > kConformTolerance * want)) continue;
    std::array<double, 4> c;
    c.fill(std::numeric_limits<double>::infinity());
    int n = 0;
    for (const int k : mids[hg.midpoint].corners)
      if (k >= 0) c[n++] = node_value_[leaf_nodes_[hg.leaf][k]];
    std::sort(c.begin(), c.end());
    // Water filling: the mean of min(cᵢ, t) is `want`; with the k smallest
    // below t, t = (n·want − Σ those) / (n − k).
    double below = 0, cap = want;
    for (int k = 0; k < n; ++k) {
      const double t = (n * want - below) / (n - k);
      if (t <= c[k]) {
        cap = t;
        break;
      }
      below += c[k];
    }
    for (const int k : mids[hg.midpoint].corners) {
      if (k < 0) continue;
      const std::uint32_t node = leaf_nodes_[hg.leaf][k];
      if (node_value_[node] > cap) {
        node_value_[node] = cap;
        node_source_[node] = node_source_[hg.node];
        moved.push_back(node);
        lowered.push_back(node);
        for (std::uint32_t q = hanging_start_[node]; q < hanging_start_[node + 1]; ++q) {
          const std::uint32_t later = hanging_of_[q];
          if (later > e && !hanging_queued_[later]) {
            hanging_queued_[later] = 1;
            ahead.push(later);
          }
        }
      }
    }
  }

  // Coarsest first: a hanging corner takes the larger octant's value. The
  // entries to redo are the first sweep's and those of the corners it lowered.
  for (const std::uint32_t e : start) hanging_queued_[e] = 1;
  for (const std::uint32_t node : lowered) enlist_all(node);
  std::priority_queue<std::uint32_t> behind(std::less<std::uint32_t>{}, std::move(start));
  while (!behind.empty()) {
    const std::uint32_t e = behind.top();
    behind.pop();
    hanging_queued_[e] = 0;
    const Hanging& hg = hanging_[e];
    const double v = interpolate(hg), old = node_value_[hg.node];
    if (v == old) continue;
    if (std::abs(v - old) > kConformTolerance * old) moved.push_back(hg.node);
    node_value_[hg.node] = v;
    for (std::uint32_t q = hanging_start_[hg.node]; q < hanging_start_[hg.node + 1]; ++q) {
      const std::uint32_t earlier = hanging_of_[q];
      if (earlier < e && !hanging_queued_[earlier]) {
        hanging_queued_[earlier] = 1;
        behind.push(earlier);
      }
    }
  }
  std::sort(moved.begin(), moved.end());
  moved.erase(std::unique(moved.begin(), moved.end()), moved.end());
  return moved;
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
  std::uint32_t o = grid_[((u[2] >> shift) * n + (u[1] >> shift)) * n + (u[0] >> shift)];
  while (octants_[o].first_child >= 0) {
    const int bit = opt_.max_depth - octants_[o].level - 1;
    const std::uint32_t child = ((u[0] >> bit) & 1u) | (((u[1] >> bit) & 1u) << 1) | (((u[2] >> bit) & 1u) << 2);
    o = static_cast<std::uint32_t>(octants_[o].first_child) + child;
  }
  return o;
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

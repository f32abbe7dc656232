// The size octree's corner sizes: assigned from the sources, graded to
// hgrad along the corner graph and made conforming at hanging corners (the
// tree itself and its queries are in octree.cpp).
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
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

namespace cm::size {

namespace {

using detail::kCorner;
using detail::kNone32;
using detail::midpoints;
using detail::morton;

// The corner graph is graded with a slightly smaller slope than hgrad asks:
// trilinear interpolation of a convex field (sizes growing away from a
// source) overshoots inside a larger octant, and between the centres of a
// large and a small neighbour that overshoot adds to the slope.
constexpr double kGradeSafety = 0.85;
// Grading and conformity are alternated until neither moves a size by more
// than this (relative); the last conformity pass is exact either way.
constexpr double kConformTolerance = 1e-7;
// Distance between corners a and b of a unit cube, indexed by a ^ b: they
// differ in 1, 2 or 3 coordinates, along an edge, a face or the body diagonal.
constexpr std::array<double, 8> kCornerDistance = {0, 1, 1, 1.4142135623730951, 1, 1.4142135623730951,
                                                   1.4142135623730951, 1.7320508075688772};

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
  tbb::parallel_sort(by_octant_.begin(), by_octant_.end(), [&](std::uint32_t a, std::uint32_t b) { return leaves_[a] < leaves_[b]; });
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
  // Distinct old corners have distinct new ids: the writes do not meet.
  tbb::parallel_for(std::size_t{0}, old_units.size(), [&](std::size_t i) {
    const auto& u = old_units[i];
    const std::int64_t id = node_of_.find(key(u[0], u[1], u[2]));
    CM_ASSERT(id >= 0);
    node_value_[static_cast<std::size_t>(id)] = old_value[i];
    node_source_[static_cast<std::size_t>(id)] = old_source[i];
  });
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

  // Hanging corners, found from the corners: a corner whose incident leaves
  // leave some of the 8 octants around it uncovered lies on the face or edge
  // of the larger leaf covering them (the tree is 2:1, so at a midpoint of
  // it). Only corners at a change of level look further than their own
  // incidence list; probing every leaf's 18 midpoints in the corner map
  // instead cost a hash lookup each, nearly all of them misses.
  const auto& mids = midpoints();
  std::array<std::int8_t, 27> mid_at;
  mid_at.fill(-1);
  for (std::size_t k = 0; k < mids.size(); ++k)
    mid_at[static_cast<std::size_t>(9 * mids[k].at[0] + 3 * mids[k].at[1] + mids[k].at[2])] = static_cast<std::int8_t>(k);
  const std::int64_t top = std::int64_t{1} << opt_.max_depth;
  // Conformity is settled finest first and, within a level, in the order
  // octants were made: lowering one face's corners changes what the next
  // face needs, so this order is part of the result. Each entry is found
  // as one integer, (deepest level first, octant, midpoint) packed into
  // 5 + 32 + 5 bits, with its node alongside: no two entries share an
  // octant and midpoint, so the corners can be searched in parallel and the
  // sorted list is the same.
  using Entry = std::pair<std::uint64_t, std::uint32_t>;
  tbb::enumerable_thread_specific<std::vector<Entry>> found_by_thread;
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, static_cast<std::uint32_t>(n), 4096),
                    [&](const tbb::blocked_range<std::uint32_t>& range) {
    std::vector<Entry>& out = found_by_thread.local();
    for (std::uint32_t v = range.begin(); v != range.end(); ++v) {
      unsigned covered = 0;
      for (std::uint32_t k = incident_start_[v]; k < incident_start_[v + 1]; ++k) covered |= 1u << ((incident_[k] & 7u) ^ 7u);
      if (covered == 0xffu) continue;
      const auto& u = node_units_[v];
      const std::uint32_t start = leaves_[incident_[incident_start_[v]] >> 3];
      std::array<std::uint32_t, 8> found{};
      int nfound = 0;
      for (unsigned b = 0; b < 8; ++b) {
        if (covered >> b & 1u) continue;
        std::array<std::int64_t, 3> p{};
        bool inside = true;
        for (int a = 0; a < 3; ++a) {
          p[a] = (b >> a & 1u) ? std::int64_t{u[a]} : std::int64_t{u[a]} - 1;
          inside = inside && p[a] >= 0 && p[a] < top;
        }
        if (!inside) continue;
        const std::uint32_t q = find_near(start, std::uint32_t(p[0]), std::uint32_t(p[1]), std::uint32_t(p[2]));
        if (std::find(found.begin(), found.begin() + nfound, q) != found.begin() + nfound) continue;
        found[static_cast<std::size_t>(nfound++)] = q;
        const Octant& o = octants_[q];
        const std::uint32_t half = units(o.level) / 2;
        const std::uint32_t at[3] = {(u[0] - o.ix) / half, (u[1] - o.iy) / half, (u[2] - o.iz) / half};
        const int k = mid_at[9 * at[0] + 3 * at[1] + at[2]];
        CM_ASSERT(k >= 0 && (u[0] - o.ix) % half == 0 && (u[1] - o.iy) % half == 0 && (u[2] - o.iz) % half == 0);
        const auto depth_first = static_cast<std::uint64_t>(opt_.max_depth - o.level);
        out.emplace_back((depth_first << 37) | (std::uint64_t{q} << 5) | static_cast<std::uint64_t>(k), v);
      }
    }
  });
  std::vector<Entry> order;
  for (const std::vector<Entry>& part : found_by_thread) order.insert(order.end(), part.begin(), part.end());
  tbb::parallel_sort(order.begin(), order.end());
  hanging_.resize(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    const auto o = static_cast<std::uint32_t>((order[i].first >> 5) & 0xffffffffu);
    hanging_[i] = {static_cast<std::uint32_t>(octant_leaf_[o]), order[i].second,
                   static_cast<std::uint8_t>(order[i].first & 31u)};
  }
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
  // The seeds, often every corner, are sorted once and merged with a heap
  // of the corners lowered on the way: the same visiting order as one heap
  // of everything (by size, then id), without sifting the seeds through it.
  std::vector<Item> initial;
  initial.reserve(seeds.size());
  for (const std::uint32_t i : seeds)
    if (node_value_[i] < opt_.hmax) initial.emplace_back(node_value_[i], i);
  tbb::parallel_sort(initial.begin(), initial.end());  // distinct ids: a total order
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  std::size_t next = 0;
  while (next < initial.size() || !queue.empty()) {
    Item item;
    if (queue.empty() || (next < initial.size() && initial[next] < queue.top())) {
      item = initial[next++];
    } else {
      item = queue.top();
      queue.pop();
    }
    const auto [h, a] = item;
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

  // Both sweeps visit the queued entries in hanging_'s order (the second in
  // reverse) and queue only entries still ahead of the one they settle, so
  // a heap of the queued entries and a scan of the flags visit the same
  // entries in the same order: the scan when a good part of them is queued.
  const auto total = static_cast<std::uint32_t>(hanging_.size());
  const auto sweep = [&](bool ascending, std::vector<std::uint32_t> queued, auto&& settle) {
    if (8 * queued.size() > total) {
      for (std::uint32_t k = 0; k < total; ++k) {
        const std::uint32_t e = ascending ? k : total - 1 - k;
        if (!hanging_queued_[e]) continue;
        hanging_queued_[e] = 0;
        settle(e, [](std::uint32_t) {});
      }
      return;
    }
    const auto later = [ascending](std::uint32_t x, std::uint32_t y) { return ascending ? x > y : x < y; };
    std::priority_queue<std::uint32_t, std::vector<std::uint32_t>, decltype(later)> heap(later, std::move(queued));
    while (!heap.empty()) {
      const std::uint32_t e = heap.top();
      heap.pop();
      hanging_queued_[e] = 0;
      settle(e, [&](std::uint32_t q) { heap.push(q); });
    }
  };

  // Finest first: where a hanging corner asks for less than a larger
  // octant interpolates there, lower that octant's corners on the face (or
  // edge) to a common cap t, the least change that makes the interpolation
  // equal to what the corner asks; corners already below t keep their size.
  std::vector<std::uint32_t> lowered;
  const auto settle_ahead = [&](std::uint32_t e, auto&& enqueue) {
    const Hanging& hg = hanging_[e];
    const double want = node_value_[hg.node];
    if (!(interpolate(hg) - want > kConformTolerance * want)) return;
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
            enqueue(later);
          }
        }
      }
    }
  };
  sweep(true, start, settle_ahead);

  // Coarsest first: a hanging corner takes the larger octant's value. The
  // entries to redo are the first sweep's and those of the corners it lowered.
  for (const std::uint32_t e : start) hanging_queued_[e] = 1;
  for (const std::uint32_t node : lowered) enlist_all(node);
  const auto settle_behind = [&](std::uint32_t e, auto&& enqueue) {
    const Hanging& hg = hanging_[e];
    const double v = interpolate(hg), old = node_value_[hg.node];
    if (v == old) return;
    if (std::abs(v - old) > kConformTolerance * old) moved.push_back(hg.node);
    node_value_[hg.node] = v;
    for (std::uint32_t q = hanging_start_[hg.node]; q < hanging_start_[hg.node + 1]; ++q) {
      const std::uint32_t earlier = hanging_of_[q];
      if (earlier < e && !hanging_queued_[earlier]) {
        hanging_queued_[earlier] = 1;
        enqueue(earlier);
      }
    }
  };
  sweep(false, std::move(start), settle_behind);
  std::sort(moved.begin(), moved.end());
  moved.erase(std::unique(moved.begin(), moved.end()), moved.end());
  return moved;
}

}  // namespace cm::size

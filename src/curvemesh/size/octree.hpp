#pragma once
// The size octree (seed paper 1, §4, "Implementation in finite octree").
//
// The root is the cube of side L around the model; an octant of level N has
// side L/2ᴺ, and a requested length ℓ at a point refines the octant there to
// level N = ⌈log₂(L/ℓ)⌉ (eq. 4.6; eqs. 4.7 and 4.8 are this N for the lengths
// of eqs. 4.3 and 4.5). Sizes live at octant corners and are interpolated
// trilinearly inside a leaf; a query reads a uniform grid of octants a few
// levels above the finest leaves and descends the rest of the way, and the
// field is continuous: a corner of a small octant lying on the face
// or edge of a larger neighbour (a hanging corner) takes the value the larger
// octant interpolates there.
//
// Requests are only recorded by insert(); build() refines for all of them at
// once, top-down over the requests sorted along the Morton curve, and keeps
// leaves and corners in that order so that neighbours are near in memory.
//
// build() then
// - balances the tree 2:1 across faces, edges and corners;
// - spreads small sizes by the gradation bound h(b) <= h(a) + (hgrad−1)|ab|
//   between the corners of every leaf (a shortest-path pass over corners);
// - keeps continuity by lowering, never raising, the corners of a larger
//   octant where a hanging corner asks for less;
// - refines every leaf whose side exceeds twice the smallest size at its
//   corners (graded sizes vary slowly; requests themselves keep eq. 4.6's
//   level) and repeats. Sizes carry over from round to round: a round
//   grades and conforms only from the corners of the leaves it made and the
//   corners its sources lowered, so its cost follows what changed.
// Every size only ever decreases from what a source asked, so the field is
// never coarser than a source at the points the source was sampled.
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/size/sampling.hpp"
#include "curvemesh/size/size_field.hpp"

namespace cm::size {

struct OctreeOptions {
  double hmin = 0;      ///< > 0; sizes below are raised to it
  /// Requests of source kCuspStrip or kThinClosedFace are raised only to this (<= hmin; 0: hmin).
  double cusp_min = 0;
  double hmax = 0;      ///< >= hmin; the size where nothing asks for less
  double hgrad = 1.3;   ///< >= 1; growth bound h(b) <= h(a) + (hgrad−1)|ab|
  int max_depth = 20;   ///< deepest level (L / 2^20 ~ 1e-6 L)
};

/// A field that can vouch for whole boxes: uniform_in(lo, hi) true means the
/// field changes value nowhere in or near the closed box, so it has one value
/// on the box and on any box that shares a point with it and is vouched for
/// too (a size inside a region, away from the region's boundary). The
/// octree then evaluates it once per connected set of such octants instead
/// of at each of their corners. False is always a correct answer.
class BoxSizeField : public SizeField {
 public:
  virtual bool uniform_in(const Vec3& lo, const Vec3& hi) const = 0;
};

class SizeOctree final : public SizeField {
 public:
  /// Root cube: centred on the box, side its largest extent plus 2%.
  /// Throws std::invalid_argument for an empty box or bad options.
  SizeOctree(const geom::BoundingBox& box, const OctreeOptions& options);

  /// Asks for size h at x (clamped to [hmin, hmax]); build() refines to eq.
  /// 4.6's level there. Where requests tie on the smallest size, the first
  /// inserted names the source.
  void insert(const Vec3& x, double h, SizeSource source);
  void insert(std::span<const SizeSample> samples);
  /// Adds a field evaluated at every octant corner and centre during build()
  /// (once per point: values are kept across refinement rounds; a
  /// BoxSizeField once per uniform set of octants); octants are refined where
  /// it asks for less than their side. Evaluated in parallel: the field must
  /// be thread-safe, and the tree is the same for any number of threads.
  void insert_field(std::shared_ptr<const SizeField> field);
  /// Balances, grades and resolves (see above). Inserting after build() is an error.
  void build();
  bool built() const { return built_; }

  double size(const Vec3& x, const SizeHint& hint = {}) const override;

  struct Leaf {
    Vec3 lo;               ///< lowest corner
    double side = 0;
    int level = 0;
    double size = 0;       ///< at the centre
    double min_size = 0;   ///< smallest at the corners
    SizeSource source = SizeSource::kHmax;  ///< what set the smallest corner
  };
  std::vector<Leaf> leaves() const;
  /// Pairs of leaves (indices into leaves()) that share part of a face.
  std::vector<std::array<std::size_t, 2>> face_neighbours() const;

  double root_side() const { return side_; }
  const Vec3& root_origin() const { return origin_; }
  std::size_t num_leaves() const { return leaf_nodes_.size(); }
  std::size_t num_corners() const { return node_value_.size(); }
  int depth() const;
  const OctreeOptions& options() const { return opt_; }
  /// Refinement rounds build() needed (balance + grade + refine).
  int build_rounds() const { return rounds_; }

 private:
  struct Octant {
    std::uint32_t ix, iy, iz;   // lowest corner in units of the finest level
    std::int32_t first_child;   // -1 for a leaf; children are contiguous, index = bx + 2by + 4bz
    std::uint8_t level;
    std::uint32_t parent;       // the root's is itself
  };
  struct Request {
    Vec3 x;
    double h;
    SizeSource source;
    int level;
  };
  using Key = std::uint64_t;
  // Values of a field at points of the finest lattice, kept across rounds:
  // most corners and centres of a round are corners of the next.
  struct FieldState {
    std::shared_ptr<const SizeField> field;
    const BoxSizeField* boxes = nullptr;  // the same field when it vouches for boxes
    std::vector<Key> keys;                // open addressing; ~0 marks an empty slot
    std::vector<double> values;
    std::size_t count = 0;
  };

  std::uint32_t units(int level) const { return std::uint32_t{1} << (opt_.max_depth - level); }
  std::array<std::uint32_t, 3> to_units(const Vec3& x) const;
  Vec3 to_point(std::uint64_t ix, std::uint64_t iy, std::uint64_t iz) const;
  static Key key(std::uint64_t ix, std::uint64_t iy, std::uint64_t iz) { return ix | (iy << 21) | (iz << 42); }
  // The leaf under octant o holding the point.
  std::uint32_t descend(std::uint32_t o, std::uint32_t ix, std::uint32_t iy, std::uint32_t iz) const;
  std::uint32_t find(std::uint32_t ix, std::uint32_t iy, std::uint32_t iz) const;
  // The leaf holding the point, found from octant `near` (up to the first
  // ancestor holding it, then down): a few steps for a neighbour's point
  // where find() walks down from the root.
  std::uint32_t find_near(std::uint32_t near, std::uint32_t ix, std::uint32_t iy, std::uint32_t iz) const;
  std::uint32_t find_leaf_fast(const std::array<std::uint32_t, 3>& u) const;
  void split(std::uint32_t octant);
  std::vector<std::uint32_t> leaf_octants() const;
  void balance(std::vector<std::uint32_t> work);
  std::vector<std::uint32_t> assign_corners();
  void evaluate_field(FieldState& state);
  void build_incidence();
  void grade(std::span<const std::uint32_t> seeds, std::vector<std::uint32_t>& changed);
  std::vector<std::uint32_t> conform(std::span<const std::uint32_t> dirty);
  std::vector<std::uint32_t> refine_to_sizes();
  void build_query_grid();

  OctreeOptions opt_;
  Vec3 origin_;
  double side_ = 0;
  std::vector<Octant> octants_;
  std::vector<Request> requests_;
  // (Morton key of the request's point, request index), sorted by build().
  std::vector<std::pair<Key, std::uint32_t>> request_order_;
  std::vector<FieldState> fields_;
  bool built_ = false;
  int rounds_ = 0;
  // Octants made before the last assign_corners(): any leaf numbered from
  // here on is new since then.
  std::uint32_t cornered_octants_ = 0;
  // Octant -> its 26 neighbours of its size exist (balance()).
  std::vector<char> balanced_parent_;

  // Corner data, rebuilt by assign_corners().
  std::vector<std::uint32_t> leaves_;                        // octant ids of the leaves, in Morton order
  // Leaf indices by increasing octant id: the order leaves() reports and
  // refinement visits them in, which depends on when octants were made and
  // not on how the leaves are laid out.
  std::vector<std::uint32_t> by_octant_;
  std::vector<std::int32_t> octant_leaf_;                    // octant -> leaf index or -1
  std::vector<std::array<std::uint32_t, 8>> leaf_nodes_;     // corner ids per leaf
  // Corner key -> corner id: open addressing, rebuilt with the corners.
  class CornerMap {
   public:
    void reset(std::size_t expected);
    /// The id stored for `k`, or `id` after storing it.
    std::uint32_t insert(Key k, std::uint32_t id);
    /// The id of `k`, or -1.
    std::int64_t find(Key k) const;

   private:
    std::size_t slot(Key k) const;
    std::vector<Key> keys_;
    std::vector<std::uint32_t> ids_;
    int shift_ = 64;
  };
  CornerMap node_of_;
  std::vector<double> leaf_side_;
  std::vector<std::array<std::uint32_t, 3>> node_units_;
  std::vector<double> node_value_;
  std::vector<SizeSource> node_source_;
  std::vector<std::uint32_t> incident_start_, incident_;  // node -> 8 * leaf + corner (CSR)
  struct Hanging {
    std::uint32_t leaf;     // the larger octant
    std::uint32_t node;     // the corner of smaller octants on its face or edge
    std::uint8_t midpoint;  // which edge midpoint or face centre
  };
  std::vector<Hanging> hanging_;  // larger octant's level descending
  // Node -> the hanging_ entries it takes part in, as the hanging corner or
  // as a corner of the larger octant (CSR): conformity revisits only those.
  std::vector<std::uint32_t> hanging_start_, hanging_of_;
  std::vector<char> hanging_queued_;
  // Point queries: the octant covering each cell of a uniform grid at level
  // grid_level_ (a leaf or an octant at that level), so that size(x) starts
  // its descent a few levels above the leaf instead of at the root.
  int grid_level_ = 0;
  std::vector<std::uint32_t> grid_;
};

}  // namespace cm::size

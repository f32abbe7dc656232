#pragma once
// Validity and acceptability of curved tets (seed paper 1, §3).
//
// An element is *valid* when det J > 0 on the whole element, which the
// certified Bézier bounds of quality/bezier_jacobian decide (kValid is a
// proof; kInvalid and kUndetermined are both treated as not valid). It is
// *acceptable* when, besides, it is not so distorted that a solver's
// quadrature misreads it:
// - the seed's measure I of eq. (3.5) (quality/shape_measure.hpp: the least
//   det J at the points of a rule exact for the volume, over its weighted
//   mean) is at least `min_measure`, and
// - the certified lower bound of the scaled Jacobian min det J / max det J is
//   at least `min_scaled_jacobian`.
// Defaults, and why: I >= 0.1 — the stiffness integrand carries 1/det J, and
// a rule exact for straight elements loses about a digit once det J varies
// tenfold between its points; a scaled Jacobian >= 0.1 is the bound the
// project's issue sets as the target wherever the geometry allows it (and
// about what Gmsh's high-order optimizer aims for). I samples, the scaled
// Jacobian bound certifies: I alone called Gmsh's folded P2 tets on the
// shared torus acceptable (I = 0.52 for one whose det J changes sign).
#include <cstdint>
#include <span>
#include <vector>

#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/quality/bezier_jacobian.hpp"

namespace cm::curved {

struct Acceptance {
  double min_measure = 0.1;          ///< I of eq. (3.5): `--min-jacobian-ratio`
  double min_scaled_jacobian = 0.1;  ///< certified lower bound of min/max det J
};

struct ElementCheck {
  quality::Validity verdict = quality::Validity::kValid;
  /// Certified lower bound of min det J / max det J (<= 0 when not valid),
  /// tightened to within 1% where it decides acceptability.
  double scaled_jacobian = 1;
  /// I of eq. (3.5), or, where it was not asked for and could not matter,
  /// a lower bound of it (see check_element).
  double measure = 1;
  bool measure_exact = true;
  /// scaled_jacobian is quality::near_straight_bounds' ratio (a
  /// quick check, check_element's `quick`), not the Bezier certification's.
  bool quick = false;
  /// Where det J is least on the reference tet (quality::SubEntity: a local
  /// vertex, edge (mesh::kTetEdges), face (mesh::kFaceVerts) or the inside).
  quality::SubEntity where{3, 0};
  bool acceptable = true;
  /// One number to rank configurations by: min(scaled_jacobian, measure),
  /// below 0 for an element that is not valid.
  double score() const { return std::min(scaled_jacobian, measure); }
};

/// Checks the order-p tet with these nodes (internal order). O(1) for a
/// tet whose nodes are all on the straight tet (then det J is constant and
/// orient3d decides); else a certification and, when `exact_measure` or
/// when acceptability needs it, an I. For a valid element I >= min det J /
/// max det J >= the certified scaled Jacobian bound, so where that bound
/// already clears min_measure, I cannot decide anything: unless asked for,
/// it is then not computed (measure = the bound, measure_exact = false):
/// det J is not evaluated at the rule's points. When it is, it comes from
/// the coefficients the certification computed (shape_measure_from_bezier).
/// For an element that is not valid, `locate_minimum` spends further
/// subdivisions moving `where` toward the least det J (and tightening the
/// negative bound); without it `where` is the first point found with
/// det J <= 0, which costs several times less: what judging the many
/// candidate configurations of a repair needs.
/// With `quick`, a tet that quality::near_straight_bounds already shows
/// acceptable with a wide margin (a scaled Jacobian bound of at least 0.5,
/// twice min_scaled_jacobian and min_measure) is taken on those bounds:
/// valid, scaled_jacobian and measure the bounds (measure_exact false,
/// quick true), at a sixth of the cost. Most boundary tets of a curved mesh
/// are such; the others are certified as without it. Where I is not
/// computed, measure is the larger of the scaled Jacobian bound and min
/// det J over mean det J (the mean of the coefficients), a tighter bound.
ElementCheck check_element(int order, std::span<const Vec3> nodes, const Acceptance& acceptance,
                           bool exact_measure = false, bool locate_minimum = true, bool quick = false);

/// check_element on tet t of m (its stored nodes; straight where none).
ElementCheck check_tet(const mesh::TetMesh& m, TetId t, const Acceptance& acceptance, bool exact_measure = false);

/// The whole mesh at once, in parallel (the result does not depend on the
/// thread count).
struct MeshCheck {
  std::vector<TetId> invalid;       ///< not certified valid (kInvalid or kUndetermined)
  std::vector<TetId> unacceptable;  ///< not acceptable (includes the invalid ones)
  std::size_t undetermined = 0;
  double min_scaled_jacobian = 1, mean_scaled_jacobian = 1;
  /// Least I of eq. (3.5) (a lower bound unless asked exact).
  double min_measure = 1;
  /// Tets checked by the quick bound alone.
  std::size_t quick = 0;
};
class CheckCache;
MeshCheck check_mesh(const mesh::TetMesh& m, const Acceptance& acceptance, bool exact_minima,
                     const CheckCache* reuse, CheckCache* keep, std::vector<ElementCheck>* first_results);

/// Check results keyed by the tet's nodes, compared exactly (never by tet
/// id, so a moved vertex or a reused id cannot hit a stale result). A
/// check_mesh can fill one with what it saw of the tets whose nodes are off
/// the straight tet, so that checking the mesh again after local changes
/// nobody tracked redoes only the tets whose nodes changed (where the
/// changes are known, recheck_mesh is cheaper); the repair uses one as a
/// memo of the candidates it judges again and again.
class CheckCache {
 public:
  CheckCache() = default;
  explicit CheckCache(int order);
  int order() const { return order_; }
  std::size_t size() const { return checks_.size(); }
  /// The result stored for exactly these nodes, if any.
  const ElementCheck* find(std::span<const Vec3> tet_nodes) const;
  /// Stores a result (the first one stays where nodes repeat).
  void add(std::span<const Vec3> tet_nodes, const ElementCheck& c);
  void clear();

 private:
  friend MeshCheck check_mesh(const mesh::TetMesh&, const Acceptance&, bool, const CheckCache*, CheckCache*,
                              std::vector<ElementCheck>*);
  void index_all();
  int order_ = 0;
  std::size_t per_tet_ = 0;
  std::vector<Vec3> nodes_;  // per_tet_ per entry
  std::vector<ElementCheck> checks_;
  // Open addressing on the node hash, the first entry with each hash (size
  // a power of two, at most half full): rebuilt for every tet of a mesh
  // check, looked up for every tet of the next one.
  static constexpr std::uint32_t kNoEntry = 0xffffffffu;
  struct Slot {
    std::uint64_t hash = 0;
    std::uint32_t entry = kNoEntry;
  };
  void insert(std::uint64_t hash, std::uint32_t entry);
  std::vector<Slot> by_hash_;
};

/// Every tet is checked with check_element's `quick`: verdicts and lists
/// are certified, each tet's scaled Jacobian is a certified lower bound
/// (the mean is the mean of those bounds), and I is computed where it
/// decides acceptability. With `exact_minima` the tets that could hold the
/// least scaled Jacobian or the least I are certified and measured in full,
/// lowest bound first, until the bounds left clear the least found (a few
/// tets): min_scaled_jacobian is then the least Bezier-certified bound over
/// the mesh (at least the full certification of every tet would give) and
/// min_measure the least I exactly (I is at least the scaled Jacobian
/// bound). With `reuse`, results of tets found there are taken as they
/// are; with `keep`, the curved tets' nodes and results are stored there;
/// with `first_results`, every tet's result as the first pass found it
/// (before the exact minima), in tet order, for recheck_mesh.
MeshCheck check_mesh(const mesh::TetMesh& m, const Acceptance& acceptance, bool exact_minima = true,
                     const CheckCache* reuse = nullptr, CheckCache* keep = nullptr,
                     std::vector<ElementCheck>* first_results = nullptr);

/// check_mesh of a mesh that an edit changed in a few places, given what
/// it was before: tet t is taken as first_results[origin[t]] of an earlier
/// check_mesh (same acceptance) where origin[t] != kNone, and checked
/// anew elsewhere. Gives what check_mesh gives, provided each origin[t]
/// names a tet that had the same nodes (as repair_curved_mesh's `origin`
/// does); its cost is the changed tets'. Throws std::invalid_argument
/// unless origin has one entry per tet.
MeshCheck recheck_mesh(const mesh::TetMesh& m, const Acceptance& acceptance, bool exact_minima,
                       std::span<const ElementCheck> first_results, std::span<const TetId> origin);

}  // namespace cm::curved

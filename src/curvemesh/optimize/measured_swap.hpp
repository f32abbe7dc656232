#pragma once
// Edge removal that chooses its triangulation by a quality the caller gives
// (the metric mean ratio in anisotropic adaptation, an angle-aware measure
// in shape improvement). modify::plan_edge_removal picks the ring
// triangulation that is best for the isotropic mean ratio, which in a
// stretched metric is often not the best one, and one that is not even
// better than the shell in the metric gets re-measured and dropped by the
// driver; here the dynamic program itself maximizes the caller's measure.
//
// Same admissibility as modify::plan_edge_removal: closed shell of 3 to
// modify::kMaxShell tets in one region, no marked face through the edge,
// every new tet strictly positive by exact orient3d (the measure must
// return a value <= 0 for a tet that is not).
#include <array>
#include <utility>

#include "curvemesh/modify/swap.hpp"

namespace cm::optimize {

/// Quality of a would-be tet given by its vertices: > 0 for a strictly
/// positive tet, higher is better; <= 0 when not strictly positive.
using TetMeasure = double (*)(const mesh::TetMesh& m, const std::array<VertId, 4>& v, const void* context);

/// The dihedral angle of a regular tet, acos(1/3), in degrees.
inline constexpr double kRegularDihedral = 70.528779365509308;

/// The shape measure of isotropic improvement: the mean ratio, or the
/// smallest dihedral angle scaled so a regular tet scores 1
/// (θ_min / acos(1/3)), whichever is lower; -1 unless strictly positive by
/// exact orient3d. A sliver can keep a fair mean ratio with a tiny angle;
/// ranking by both makes the angle count where it is the problem.
double angle_aware_quality(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);
/// Whether angle_aware_quality(a, b, c, d) >= q for certain, by cheap
/// bounds (quality::tet_mean_ratio_at_least, tet_min_dihedral_at_least);
/// false means "maybe not": compute it. For the search of a worst tet.
bool angle_aware_quality_at_least(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double q);
/// angle_aware_quality of mesh vertices, as a TetMeasure (context unused).
double angle_aware_measure(const mesh::TetMesh& m, const std::array<VertId, 4>& v, const void* context);

/// The floor of is_progress (both measures).
inline constexpr double kProgressFloor = 0.2;
/// The mean ratio floor while the worst tet has a dihedral angle under 10°:
/// a tet on a thin boundary triangle (a needle at a small model feature,
/// the corner of a face whose edges meet tangentially) reaches 10° only as
/// a spindle, whose mean ratio is low. On the shared models this takes t20
/// at hmax 1.68 from 7.8° to 12.4° (mean ratio 0.20 -> 0.17) and Gmsh's
/// unoptimized Zylkopf mesh, surface fixed, from 6.5° to 10.6° (0.197 ->
/// 0.150).
inline constexpr double kRescueFloor = 0.15;

/// The mean ratio is_progress lets a change fall to when it raises the
/// worst angle-aware quality from shape_before: the lower of mr_before and
/// kProgressFloor, or of mr_before and kRescueFloor while shape_before is
/// that of a tet under 10°.
double mean_ratio_floor(double mr_before, double shape_before);

/// Mean ratio and angle_aware_quality of one tet (both -1 unless strictly
/// positive by exact orient3d), for searches that must keep the first
/// above a floor while raising the second.
std::pair<double, double> mean_ratio_and_shape(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// worst = the elementwise minimum of worst and mean_ratio_and_shape(a, b,
/// c, d), the same bits, but without computing either measure where a cheap
/// bound shows the tet cannot lower it: most tets of a star or ball are far
/// from its worst.
void fold_mean_ratio_and_shape(std::pair<double, double>& worst, const Vec3& a, const Vec3& b, const Vec3& c,
                               const Vec3& d);

/// mean_ratio_and_shape with the tet's least dihedral angle (degrees,
/// quality::tet_min_dihedral, whatever the orientation), which the shape
/// is computed from: one evaluation where a judge needs all three.
struct TetShape {
  double mean_ratio, shape, min_dihedral;
};
TetShape tet_shape(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// The shape of a needle of a cusp tip's fan, which is judged by its angle
/// alone (its mean ratio is low by design): θ_min / acos(1/3), -1 unless
/// strictly positive.
inline double needle_shape(const TetShape& q) { return q.shape > 0 ? q.min_dihedral / kRegularDihedral : -1.0; }

/// Whether replacing tets whose worst mean ratio and worst angle-aware
/// quality are (mr_before, shape_before) by tets with (mr_after,
/// shape_after) is progress: one of the two rises and the other does not
/// fall below the lower of its old value and a floor (0.2 for both: a mean
/// ratio that no one calls poor; θ_min ≈ 14°; for the mean ratio
/// kRescueFloor while the angle is under 10°: mean_ratio_floor). Ranking by
/// the angle alone trades mean ratio away for spindles (fair angles, tiny
/// volume), by the mean ratio alone leaves slivers that keep a fair one.
bool is_progress(double mr_before, double shape_before, double mr_after, double shape_after);

/// Plans the removal of edge (a, b) of live tet `start`, maximizing the
/// worst `measure` of the new tets; plan.before / after are in that
/// measure. Fills the cavity with the shell; changes nothing. Apply with
/// modify::apply(ed, cavity, plan). O(n³) measure calls for a shell of n.
modify::Plan plan_measured_edge_removal(modify::MeshEditor& ed, modify::Cavity& cavity, VertId a, VertId b,
                                        TetId start, TetMeasure measure, const void* context);

/// The 2-3 swap of face f of t, measured the same way.
modify::Plan plan_measured_face_swap(modify::MeshEditor& ed, modify::Cavity& cavity, TetId t, int f,
                                     TetMeasure measure, const void* context);

}  // namespace cm::optimize

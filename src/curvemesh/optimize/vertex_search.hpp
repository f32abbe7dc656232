#pragma once
// Relocation by local search of the worst tet (paper 2's point relocation,
// with the position optimized rather than guessed). The smart Laplacian of
// modify/relocate.hpp moves a vertex toward a centroid: right for a ball of
// fair tets, of no use for a sliver whose vertex sits near the plane of the
// other three, which needs the vertex moved off that plane, nor for a ball
// whose worst tet is not where the centroid pulls. Here the vertex goes
// where the worst angle-aware quality of its ball (measured_swap.hpp) is
// highest, found by a compass search: polls along the coordinate directions
// of the vertex's entity, along the normal that lifts the worst tet's vertex
// off its opposite face and toward the ball's centroid, the step halved
// when no poll improves.
//
// A region vertex moves freely; with a model, a vertex on a model face
// moves in the face's tangent plane at its start, each poll projected back
// onto the face (closest point hinted by its parameters), and a vertex on a
// model edge along the edge's tangent, projected onto the edge. Model
// vertices never move. Validity is exact (every poll's tets are measured
// with orient3d first), and the winner goes through
// modify::plan_relocation_to (positivity, boundary triangles kept on their
// side and against the model as the boundary check judges them).
#include <span>

#include "curvemesh/geom/cusps.hpp"
#include "curvemesh/geom/model.hpp"
#include "curvemesh/modify/relocate.hpp"

namespace cm::optimize {

/// Plans moving v by the search. Fills the cavity with v's ball; changes
/// nothing (coordinates are restored after each poll). Only positions where
/// the ball's worst mean ratio stays at or above mean_ratio_floor of its
/// worst now (what is_progress accepts) are considered; among
/// them the search raises the ball's worst angle-aware quality up to that
/// of a tet whose smallest dihedral angle is `angle_goal` degrees, then
/// (the angles being good enough) the worst mean ratio. Refusals: those of
/// modify::plan_relocation_to for the winner, and kNoImprovement when
/// neither rises by more than 1e-6.
/// plan.before / after are the ball's worst tet_quality (mean ratio) now
/// and at the target. Costs at most `max_polls` evaluations of the ball
/// (each, for a boundary vertex, one closest-point query).
/// With `keep_out` (cusp tips' balls, which hold no point but their vertex)
/// no poll lands inside a ball: a region vertex's poll there is taken out
/// to the ball's sphere along the ray from its centre, so a point of a tip's
/// cap slides over the cap (the moves that reshape the cap's triangles,
/// whose angles are the needles' dihedral angles); any other is refused.
/// A region vertex on a ball's sphere (a point of its cap) polls only on
/// that sphere, and its tets at the ball's centre (needles) are ranked by
/// their smallest dihedral angle alone, outside the mean ratio floor.
modify::Relocation plan_searched_relocation(modify::MeshEditor& ed, modify::Cavity& cavity,
                                            const modify::BoundaryIndex* boundary, VertId v,
                                            const geom::Model* model, double angle_goal = 12,
                                            int max_polls = 40, const geom::TipBalls* keep_out = nullptr);

/// The point x where the worst angle-aware quality of the star of x over
/// `faces` (a cavity's boundary, each face's normal out of the cavity, as
/// modify::CavityFace lists it) is highest, up to the `angle_goal` as above
/// and then the worst mean ratio, among the points where no star tet's mean
/// ratio is below `mean_ratio_floor`, by the same compass search
/// from `start` (polls along the axes and lifting the worst tet's apex off
/// its face). Returns start when no poll beats it. At most `max_polls`
/// evaluations of the star. For point insertion (shell_insert.hpp).
Vec3 search_star_point(const mesh::TetMesh& m, std::span<const modify::CavityFace> faces, const Vec3& start,
                       double mean_ratio_floor, double angle_goal = 12, int max_polls = 60);

}  // namespace cm::optimize

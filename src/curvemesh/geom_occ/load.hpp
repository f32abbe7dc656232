#pragma once
// Loading CAD models into a geom::Model backed by OpenCASCADE. This header is
// the whole public surface of geom_occ: no OpenCASCADE type appears here.
//
// What load_model does, in order:
//  1. Read. STEP (.step/.stp), IGES (.iges/.igs) and OCC B-rep (.brep) files,
//     chosen by extension (case-insensitive), or a built-in shape
//     ("builtin:NAME[:key=value,...]", see builtin_help()).
//  2. Keep the file's length unit. Coordinates are NOT scaled: a STEP file in
//     inches gives a model in inches and units() reports "inch". STEP and IGES
//     report their declared unit ("mm", "cm", "m", "inch", "ft", ...; the first
//     one if a STEP file declares several); B-rep files and built-ins carry no
//     unit and report "".
//  3. Heal (LoadOptions::heal): ShapeFix_Shape, run when BRepCheck finds the
//     shape invalid or an explicit heal_tolerance asks for it. A valid shape is
//     left alone, so that tags follow the file (healing renumbers entities);
//     the STEP and IGES translators heal what they read anyway.
//  4. Make solids. Solids in the file are used as they are (free faces, wires
//     and points outside any solid are dropped: a volume mesher cannot use
//     them). A file with faces or shells but no solid is sewn
//     (LoadOptions::sew) and each closed shell becomes a solid; an open shell
//     is a GeometryError naming a face with a free edge.
//  5. Make several solids conformal: a general fuse (BOPAlgo_Builder) keeps the
//     solids separate but splits and merges their boundaries, so a face two
//     solids share is ONE model face bounding both regions. Overlapping solids
//     come out as their pieces (A\B, A∩B, B\A), each a region.
//
// Tags are TopExp::MapShapes indices over the final shape (stable for the same
// input and options): for a valid single-solid file, the indices TopExp gives
// over the file's solid. The healing tolerance is LoadOptions::heal_tolerance, or
// when 0 the largest vertex tolerance of the model (at least 1e-7).
//
// Model conventions beyond geom::Model:
// - tolerance(edge) is the B-rep tolerance raised to the measured gap between
//   the edge's 3D curve and its p-curves: files often understate it (the
//   shared STEP models by up to 1e5 times). tolerance(region) is the largest
//   tolerance of its faces.
// - contains_param counts as inside a band around the boundary as wide as the
//   face's and its edges' tolerance (in (u, v) through the surface's
//   resolution), and at least the largest gap between consecutive p-curves
//   of a loop.
// - closest_point on a face returns (u, v) inside the trimmed face; when the
//   unconstrained closest point of the surface is trimmed away, the closest
//   point of the face's boundary as the p-curves draw it.
// - type() of a degenerate edge is kPoint. bounding_box of an edge is exact
//   (BRepBndLib optimal); of a face, its edges' boxes plus the interior
//   extreme points found by ascent from a sample grid; of a region, the union
//   of its faces'.
// - area, volume and center_of_mass (BRepGProp) are computed on first use.
// - classify_point answers in three tiers, each only where it is sure. The
//   first call on a region tessellates a copy of it (BRepMesh, deflection
//   1e-3 of its diagonal; 20-300 ms on the shared models) and measures how
//   far each triangle strays from its face. Outside every triangle's band
//   (twice that, plus twice the tolerance of the face, its edges and
//   vertices): ray parity on the triangles, two of three fixed rays
//   agreeing, about 2-5 us. In a band: the closest point of the nearby faces
//   and the side of the outward normal there (of the two normals' sum on an
//   edge; kOn within tolerance({3, region})), tens of microseconds.
//   Otherwise (corners, rays grazing a triangle): BRepClass3d_SolidClassifier
//   with tolerance({3, region}), 0.05-7 ms per call on the shared models,
//   one classifier per concurrent caller. Over uniform points in the box
//   (bench_geometry BM_ClassifyPoint) 2-6 us of CPU per call on average;
//   about 0.1% of calls reach the last tier.
//
// Thread safety: load_model may be called from several threads, but the
// STEP/IGES readers share process-wide XSTEP settings, so file reading is
// serialized by an internal mutex. The returned model answers queries from any
// number of threads at once (see geom::Model).
#include <memory>
#include <string>

#include "curvemesh/geom/model.hpp"

namespace cm::geom_occ {

struct LoadOptions {
  /// Healing and sewing tolerance in model units; 0: taken from the model.
  double heal_tolerance = 0;
  /// Run shape healing (ShapeFix) before building the model.
  bool heal = true;
  /// Sew free faces and open shells into solids when the file has no solid.
  bool sew = true;
};

/// Loads MODEL: a file path (.step/.stp, .iges/.igs, .brep, by extension,
/// case-insensitive) or a built-in "builtin:NAME[:key=value,...]" (box,
/// sphere, cylinder, torus, cone, part; blocks and inclusion have two
/// regions).
/// Throws cm::InputError for a missing, empty or unreadable file, content that
/// does not match the extension, an unknown built-in or parameter; throws
/// cm::GeometryError when the model has no solid or cannot be made into
/// closed solids (the message names the entity).
std::unique_ptr<geom::Model> load_model(const std::string& model, const LoadOptions& options = {});

/// The built-in names with their parameters and defaults, one per line, for --help.
std::string builtin_help();

}  // namespace cm::geom_occ

// classify_point of OccModel, in three tiers, each taken only when it is
// sure of its answer:
//  1. away from the boundary (outside every triangle's band): ray parity on
//     a tessellation of the region's boundary, a few microseconds;
//  2. in the band: the closest point of the nearby faces (started from
//     their nearest triangles) and the side of the outward normal there, or
//     of the two normals at an edge, tens of microseconds;
//  3. otherwise (near a corner, thin walls, rays grazing a triangle):
//     BRepClass3d_SolidClassifier on the solid, milliseconds on CAD models,
//     one classifier per concurrent caller (ClassifierPool).
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <BRepBuilderAPI_Copy.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <Geom_Surface.hxx>
#include <Poly_Triangulation.hxx>
#include <Standard_Failure.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Vec.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/occ_model.hpp"

namespace cm::geom_occ::detail {

namespace {

// Linear deflection of the tessellation, relative to the region's box
// diagonal. Finer narrows the band around curved faces (fewer points for
// the slower tiers) but costs triangles and set-up time about as fast: on
// the shared models 2e-4 halved the points in the band for 2-4 times the
// triangles.
constexpr double kRelativeDeflection = 1e-3;
constexpr double kAngularDeflection = 0.5;
// Tier 2 trusts a closest point only where the point lies along the face
// normal there (an interior foot, not one clamped to the face's boundary).
constexpr double kNormalAlignment = 0.999;

Vec3 to_vec(const gp_Pnt& p) { return {p.X(), p.Y(), p.Z()}; }

/// A classifier borrowed from a pool for one query. It goes back to the
/// pool only after a clean Perform: one interrupted by an exception may have
/// left its explorer mid-walk, so it is dropped instead.
class BorrowedClassifier {
 public:
  BorrowedClassifier(ClassifierPool& pool, const TopoDS_Solid& solid) : pool_(pool) {
    {
      const std::lock_guard<std::mutex> lock(pool_.mutex);
      if (!pool_.idle.empty()) {
        classifier_ = std::move(pool_.idle.back());
        pool_.idle.pop_back();
      }
    }
    // Built outside the lock: loading a solid of many faces takes a while
    // and other callers need not wait for it.
    if (!classifier_) classifier_ = std::make_unique<BRepClass3d_SolidClassifier>(solid);
  }
  BorrowedClassifier(const BorrowedClassifier&) = delete;
  BorrowedClassifier& operator=(const BorrowedClassifier&) = delete;
  ~BorrowedClassifier() {
    if (!done_) return;
    const std::lock_guard<std::mutex> lock(pool_.mutex);
    pool_.idle.push_back(std::move(classifier_));
  }

  TopAbs_State classify(const Vec3& x, double tolerance) {
    classifier_->Perform(gp_Pnt(x.x(), x.y(), x.z()), tolerance);
    done_ = true;
    return classifier_->State();
  }

 private:
  ClassifierPool& pool_;
  std::unique_ptr<BRepClass3d_SolidClassifier> classifier_;
  bool done_ = false;
};

// At a pole or apex one parameter does not move the point, and BRepMesh
// gives the node an arbitrary value of it (u = 0 at a sphere's pole). For
// interpolating inside a triangle, that value is taken from its neighbours.
void fix_singular_parameters(const Geom_Surface& surface, std::array<Vec2, 3>& uv) {
  std::array<Vec2, 3> fixed = uv;
  for (int k = 0; k < 3; ++k) {
    gp_Pnt p;
    gp_Vec du, dv;
    surface.D1(uv[k].x(), uv[k].y(), p, du, dv);
    const double scale = std::max(du.Magnitude(), dv.Magnitude());
    if (!(scale > 0)) continue;
    const Vec2 others = 0.5 * (uv[(k + 1) % 3] + uv[(k + 2) % 3]);
    if (du.Magnitude() < 1e-9 * scale) fixed[k].x() = others.x();
    if (dv.Magnitude() < 1e-9 * scale) fixed[k].y() = others.y();
  }
  uv = fixed;
}

}  // namespace

// Tessellates a copy of the solid (the model's faces stay untouched: other
// threads read them, and a triangulation attached to a face changes what
// some OCC algorithms do with it) and measures how far each triangle strays
// from its face: at its centroid and edge midpoints, against the surface at
// the matching (u, v). Any failure leaves tiers 1 and 2 off.
RegionMesh OccModel::build_region_mesh(int region) const {
  const RegionData& r = regions_[static_cast<std::size_t>(region - 1)];
  RegionMesh out;
  const double diagonal = r.box.diagonal();
  if (!(diagonal > 0) || !std::isfinite(diagonal)) return out;
  // Per face: the uncertainty of where its boundary is (its own, its edges'
  // and its vertices' tolerances), never below the region's kOn band.
  const auto face_tolerance = [&](int tag) {
    const FaceData& face = faces_[static_cast<std::size_t>(tag - 1)];
    double tolerance = std::max(r.tolerance, face.tolerance);
    for (const int e : face.edges) {
      const EdgeData& edge = edges_[static_cast<std::size_t>(e - 1)];
      tolerance = std::max(tolerance, edge.tolerance);
      for (const int v : edge.vertices)
        if (v > 0) tolerance = std::max(tolerance, vertices_[static_cast<std::size_t>(v - 1)].tolerance);
    }
    return tolerance;
  };
  try {
    BRepBuilderAPI_Copy copier(r.solid, true, false);
    const BRepMesh_IncrementalMesh mesher(copier.Shape(), kRelativeDeflection * diagonal, false, kAngularDeflection,
                                          false);
    if (!mesher.IsDone()) return out;
    std::vector<TriangleClassifier::Triangle> triangles;
    // Every use: a face inside the solid (both sides in it) is crossed twice.
    for (const geom::OrientedUse& use : r.faces) {
      const double tolerance = face_tolerance(use.tag);
      out.tolerance = std::max(out.tolerance, tolerance);
      // Absolute floor of the band: points this close are kOn, which only
      // tiers 2 and 3 tell.
      const double floor = 2 * tolerance + 1e-9 * diagonal;
      const TopoDS_Face face = TopoDS::Face(copier.ModifiedShape(faces_[static_cast<std::size_t>(use.tag - 1)].face));
      TopLoc_Location location;
      const Handle(Poly_Triangulation) mesh = BRep_Tool::Triangulation(face, location);
      // A face left out would open the surface and break the parity.
      if (mesh.IsNull() || mesh->NbTriangles() == 0 || !mesh->HasUVNodes()) return out;
      const gp_Trsf to_model = location.Transformation();
      const Handle(Geom_Surface) surface = BRep_Tool::Surface(face);  // located
      for (int t = 1; t <= mesh->NbTriangles(); ++t) {
        int n[3];
        mesh->Triangle(t).Get(n[0], n[1], n[2]);
        TriangleClassifier::Triangle tri;
        tri.face = use.tag;
        for (int k = 0; k < 3; ++k) {
          tri.corners[k] = to_vec(mesh->Node(n[k]).Transformed(to_model));
          const gp_Pnt2d p = mesh->UVNode(n[k]);
          tri.uv[k] = Vec2(p.X(), p.Y());
        }
        fix_singular_parameters(*surface, tri.uv);
        double deviation = 0;
        const auto stray = [&](const Vec2& at, const Vec3& on_triangle) {
          deviation = std::max(deviation, (to_vec(surface->Value(at.x(), at.y())) - on_triangle).norm());
        };
        const auto& c = tri.corners;
        stray((tri.uv[0] + tri.uv[1] + tri.uv[2]) / 3, (c[0] + c[1] + c[2]) / 3);
        for (int k = 0; k < 3; ++k) stray((tri.uv[k] + tri.uv[(k + 1) % 3]) / 2, (c[k] + c[(k + 1) % 3]) / 2);
        // Doubled: the samples see most, not all, of the gap between a
        // curved patch and its triangle.
        tri.band = 2 * deviation + floor;
        out.band = std::max(out.band, tri.band);
        triangles.push_back(tri);
      }
    }
    out.surface = std::make_unique<TriangleClassifier>(std::move(triangles));
  } catch (const Standard_Failure&) {
    return {};
  }
  return out;
}

// Tier 2. x is within the band. The faces that may hold its closest
// boundary point are those whose triangles reach within the nearest
// triangle's distance plus the bands; x is projected on each (from its
// nearest triangle's (u, v)), and the nearest foot p decides by the side of
// the outward normal there, which is exact when p is the closest point of
// the whole boundary: the open ball through p around x then meets no
// boundary, so the segment from x to p crosses none. Two faces tying is p on
// their common edge, where the sum of their normals tells the side (the
// edge's pseudo-normal); anything else (a corner, a projection that
// disagrees with the tessellation, a foot not along the normal) goes to
// tier 3.
std::optional<geom::Containment> OccModel::classify_near_faces(const RegionData& region, const RegionMesh& mesh,
                                                               const Vec3& x) const {
  constexpr std::size_t kMaxFaces = 16;
  const std::optional<TriangleClassifier::Nearest> nearest = mesh.surface->nearest(x);
  if (!nearest) return std::nullopt;
  const std::vector<TriangleClassifier::Nearest> near =
      mesh.surface->faces_within(x, nearest->distance + nearest->triangle->band, kMaxFaces);
  if (near.empty() || near.size() > kMaxFaces) return std::nullopt;
  struct Foot {
    geom::Projection projection;
    int face = 0;
    const TriangleClassifier::Nearest* triangle = nullptr;  // the face's triangle nearest to x
  };
  std::vector<Foot> feet;
  double widest_band = 0;
  for (const TriangleClassifier::Nearest& n : near) {
    const TriangleClassifier::Triangle& t = *n.triangle;
    const Vec3& w = n.barycentric;
    const Vec2 hint = w[0] * t.uv[0] + w[1] * t.uv[1] + w[2] * t.uv[2];
    feet.push_back({project_on_face(faces_[static_cast<std::size_t>(t.face - 1)], x, hint), t.face, &n});
    widest_band = std::max(widest_band, t.band);
  }
  const auto best = std::min_element(feet.begin(), feet.end(), [](const Foot& a, const Foot& b) {
    return a.projection.distance < b.projection.distance;
  });
  const double distance = best->projection.distance;
  // Within the tolerance of a point of the boundary: on it, by definition.
  if (distance <= region.tolerance) return geom::Containment::kOn;
  // The foot must be where the tessellation says the face is nearest: a
  // projection that slid to another part of its face (around a thin wall)
  // proves nothing.
  if (std::abs(distance - nearest->distance) > widest_band ||
      std::abs(distance - best->triangle->distance) > best->triangle->triangle->band)
    return std::nullopt;
  const auto outward = [&](const Foot& f) {
    const Vec3 n = face_normal(f.face, f.projection.param);
    for (const geom::OrientedUse& use : region.faces)
      if (use.tag == f.face && !use.forward) return Vec3(-n);
    return n;
  };
  const Vec3 offset = x - best->projection.point;
  // An interior foot: x lies along the normal there.
  const double along = offset.dot(outward(*best));
  if (std::abs(along) >= kNormalAlignment * distance)
    return along > 0 ? geom::Containment::kOutside : geom::Containment::kInside;
  // A foot on the face's boundary: the faces whose feet are the same point
  // (to the accuracy of the p-curves, as far apart as the edge tolerances)
  // meet there. Two: an edge, whose pseudo-normal is the sum of theirs.
  const double tie = mesh.tolerance + 1e-9 * distance;
  Vec3 normal = Vec3::Zero();
  int meeting = 0;
  for (const Foot& f : feet) {
    if (f.projection.distance > distance + tie || (f.projection.point - best->projection.point).norm() > 2 * tie)
      continue;
    normal += outward(f);
    ++meeting;
  }
  if (meeting == 2 && normal.norm() > 1e-6) {
    const double side = offset.dot(normal.normalized());
    if (std::abs(side) < 1e-3 * distance) return std::nullopt;
    return side > 0 ? geom::Containment::kOutside : geom::Containment::kInside;
  }
  return std::nullopt;
}

geom::Containment OccModel::classify_point(int region, const Vec3& x) const {
  const RegionData& r = region_at(region);
  if (!x.allFinite())
    throw std::invalid_argument(fmt::format("region {}: classify_point at a non-finite point ({}, {}, {})", region,
                                            x.x(), x.y(), x.z()));
  const RegionMesh& mesh = region_meshes_[region - 1].get([&] { return build_region_mesh(region); });
  if (mesh.surface) {
    if (!mesh.surface->in_band(x)) {
      if (const std::optional<bool> in = mesh.surface->inside(x))
        return *in ? geom::Containment::kInside : geom::Containment::kOutside;
    } else {
      try {
        if (const std::optional<geom::Containment> c = classify_near_faces(r, mesh, x)) return *c;
      } catch (const GeometryError&) {
        // No usable normal or projection there: tier 3 decides.
      }
    }
  }
  TopAbs_State state = TopAbs_UNKNOWN;
  try {
    BorrowedClassifier classifier(*r.classifiers, r.solid);
    state = classifier.classify(x, r.tolerance);
  } catch (const Standard_Failure& e) {
    throw GeometryError(fmt::format("region {}: cannot classify ({}, {}, {}): {}", region, x.x(), x.y(), x.z(),
                                    e.GetMessageString()));
  }
  switch (state) {
    case TopAbs_IN: return geom::Containment::kInside;
    case TopAbs_OUT: return geom::Containment::kOutside;
    case TopAbs_ON: return geom::Containment::kOn;
    default: break;
  }
  throw GeometryError(fmt::format("region {}: the solid classifier cannot tell where ({}, {}, {}) is", region,
                                  x.x(), x.y(), x.z()));
}

}  // namespace cm::geom_occ::detail

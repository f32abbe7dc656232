// OccModel construction: the entity tables filled once from the final shape,
// and the topology queries answered from them.
#include "curvemesh/geom_occ/detail/occ_model.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepBndLib.hxx>
#include <BRepGProp.hxx>
#include <BRepLib.hxx>
#include <BRepTools.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Precision.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Vec.hxx>
#include <tbb/parallel_for.h>

#include "curvemesh/core/error.hpp"

namespace cm::geom_occ::detail {

namespace {

using geom::ShapeType;

Vec3 to_vec(const gp_Pnt& p) { return {p.X(), p.Y(), p.Z()}; }

geom::BoundingBox to_box(const Bnd_Box& b) {
  geom::BoundingBox box;
  if (b.IsVoid()) return box;
  double x0, y0, z0, x1, y1, z1;
  b.Get(x0, y0, z0, x1, y1, z1);
  box.add({x0, y0, z0});
  box.add({x1, y1, z1});
  return box;
}

geom::BoundingBox optimal_box(const TopoDS_Shape& shape) {
  Bnd_Box b;
  // Exact geometry, not the (possibly absent) triangulation, and no tolerance
  // padding: the box is a geometric fact about the entity.
  BRepBndLib::AddOptimal(shape, b, false, false);
  return to_box(b);
}

ShapeType curve_type(GeomAbs_CurveType t) {
  switch (t) {
    case GeomAbs_Line: return ShapeType::kLine;
    case GeomAbs_Circle: return ShapeType::kCircle;
    case GeomAbs_Ellipse: return ShapeType::kEllipse;
    case GeomAbs_BSplineCurve: return ShapeType::kBSplineCurve;
    case GeomAbs_BezierCurve: return ShapeType::kBezierCurve;
    default: return ShapeType::kOtherCurve;
  }
}

ShapeType surface_type(GeomAbs_SurfaceType t) {
  switch (t) {
    case GeomAbs_Plane: return ShapeType::kPlane;
    case GeomAbs_Cylinder: return ShapeType::kCylinder;
    case GeomAbs_Cone: return ShapeType::kCone;
    case GeomAbs_Sphere: return ShapeType::kSphere;
    case GeomAbs_Torus: return ShapeType::kTorus;
    case GeomAbs_BSplineSurface: return ShapeType::kBSplineSurface;
    case GeomAbs_BezierSurface: return ShapeType::kBezierSurface;
    case GeomAbs_SurfaceOfRevolution: return ShapeType::kSurfaceOfRevolution;
    case GeomAbs_SurfaceOfExtrusion: return ShapeType::kSurfaceOfExtrusion;
    case GeomAbs_OffsetSurface: return ShapeType::kOffsetSurface;
    default: return ShapeType::kOtherSurface;
  }
}

std::vector<int> ancestor_tags(const TopTools_IndexedDataMapOfShapeListOfShape& ancestors,
                               const TopoDS_Shape& shape, const TopTools_IndexedMapOfShape& up) {
  std::vector<int> tags;
  const int index = ancestors.FindIndex(shape);
  if (index == 0) return tags;
  for (const TopoDS_Shape& a : ancestors(index)) {
    const int tag = up.FindIndex(a);
    if (tag > 0) tags.push_back(tag);
  }
  std::sort(tags.begin(), tags.end());
  tags.erase(std::unique(tags.begin(), tags.end()), tags.end());
  return tags;
}

// Number of seed samples along a parameter direction: enough to put a few in
// every B-spline span so that Newton starts in the right basin.
int samples_for_knots(int knots, int degree) {
  return std::clamp((knots - 1) * std::max(2, degree) + 1, 13, 41);
}

std::string entity_name(int dim, int tag) {
  static const char* const kNames[] = {"vertex", "edge", "face", "region"};
  return fmt::format("{} {}", kNames[dim], tag);
}

}  // namespace

OccModel::OccModel(const TopoDS_Shape& solids, std::string units) : units_(std::move(units)) {
  ShapeMaps maps;
  TopExp::MapShapes(solids, TopAbs_VERTEX, maps.vertices);
  TopExp::MapShapes(solids, TopAbs_EDGE, maps.edges);
  TopExp::MapShapes(solids, TopAbs_FACE, maps.faces);
  TopExp::MapShapes(solids, TopAbs_SOLID, maps.solids);
  build_vertices(solids, maps);
  build_edges(solids, maps);
  build_regions(maps);
  build_faces(solids, maps);
  face_areas_ = std::make_unique<Lazy<double>[]>(faces_.size());
  region_mass_ = std::make_unique<Lazy<MassProperties>[]>(regions_.size());
  region_meshes_ = std::make_unique<Lazy<RegionMesh>[]>(regions_.size());
  for (const RegionData& r : regions_) {
    box_.add(r.box.min);
    box_.add(r.box.max);
  }
  scale_ = std::max(box_.diagonal(), 1e-300);
  static std::atomic<std::uint64_t> next_serial{1};
  serial_ = next_serial++;
}

void OccModel::build_vertices(const TopoDS_Shape& shape, const ShapeMaps& maps) {
  TopTools_IndexedDataMapOfShapeListOfShape v2e;
  TopExp::MapShapesAndAncestors(shape, TopAbs_VERTEX, TopAbs_EDGE, v2e);
  vertices_.resize(maps.vertices.Extent());
  for (int i = 1; i <= maps.vertices.Extent(); ++i) {
    const TopoDS_Vertex& v = TopoDS::Vertex(maps.vertices(i));
    VertexData& d = vertices_[i - 1];
    d.point = to_vec(BRep_Tool::Pnt(v));
    d.tolerance = BRep_Tool::Tolerance(v);
    d.edges = ancestor_tags(v2e, v, maps.edges);
  }
}

void OccModel::build_edges(const TopoDS_Shape& shape, const ShapeMaps& maps) {
  TopTools_IndexedDataMapOfShapeListOfShape e2f;
  TopExp::MapShapesAndAncestors(shape, TopAbs_EDGE, TopAbs_FACE, e2f);
  edges_.resize(maps.edges.Extent());
  for (int i = 1; i <= maps.edges.Extent(); ++i) {
    EdgeData& d = edges_[i - 1];
    d.edge = TopoDS::Edge(maps.edges(i).Oriented(TopAbs_FORWARD));
    d.degenerate = BRep_Tool::Degenerated(d.edge);
    TopoDS_Vertex v0, v1;
    TopExp::Vertices(d.edge, v0, v1);
    d.vertices = {v0.IsNull() ? 0 : maps.vertices.FindIndex(v0),
                  v1.IsNull() ? 0 : maps.vertices.FindIndex(v1)};
    d.tolerance = BRep_Tool::Tolerance(d.edge);
    d.faces = ancestor_tags(e2f, d.edge, maps.faces);
    BRep_Tool::Range(d.edge, d.first, d.last);
    d.range.u0 = d.first;
    d.range.u1 = d.last;
    if (d.degenerate) {
      d.type = ShapeType::kPoint;
      const Vec3 p = d.vertices[0] > 0 ? vertices_[d.vertices[0] - 1].point : Vec3::Zero();
      d.box.add(p);
      d.sample_params = {d.first};
      d.sample_points = {p};
      continue;
    }
    double first = 0, last = 0;
    d.curve = BRep_Tool::Curve(d.edge, first, last);
    if (d.curve.IsNull()) {
      // Some IGES/STEP edges carry only p-curves; the mesher needs 3D points.
      BRepLib::BuildCurve3d(d.edge);
      d.curve = BRep_Tool::Curve(d.edge, first, last);
      if (d.curve.IsNull())
        throw GeometryError(fmt::format("{} has no 3D curve and none can be built",
                                        entity_name(1, i)));
    }
    while (auto trimmed = Handle(Geom_TrimmedCurve)::DownCast(d.curve)) d.curve = trimmed->BasisCurve();
    d.eval = CurveEvaluator(d.curve);
    d.type = curve_type(BRepAdaptor_Curve(d.edge).GetType());
    if (d.curve->IsPeriodic() && d.vertices[0] == d.vertices[1]) {
      const double period = d.curve->Period();
      if (std::abs((d.last - d.first) - period) <= 1e-9 * period) {
        d.range.periodic_u = true;
        d.range.period_u = period;
      }
    }
    GProp_GProps props;
    BRepGProp::LinearProperties(d.edge, props);
    d.length = props.Mass();
    d.box = optimal_box(d.edge);
    int n = 17;
    if (auto bspline = Handle(Geom_BSplineCurve)::DownCast(d.curve))
      n = std::max(n, samples_for_knots(bspline->NbKnots(), bspline->Degree()));
    d.sample_params.resize(n);
    d.sample_points.resize(n);
    for (int k = 0; k < n; ++k) {
      const double u = d.first + (d.last - d.first) * k / (n - 1);
      d.sample_params[k] = u;
      d.sample_points[k] = to_vec(d.eval.value(u));
    }
  }
}

void OccModel::build_regions(const ShapeMaps& maps) {
  regions_.resize(maps.solids.Extent());
  for (int i = 1; i <= maps.solids.Extent(); ++i) {
    RegionData& d = regions_[i - 1];
    d.solid = TopoDS::Solid(maps.solids(i));
    for (TopExp_Explorer shell(d.solid, TopAbs_SHELL); shell.More(); shell.Next()) {
      for (TopoDS_Iterator it(shell.Current()); it.More(); it.Next()) {
        if (it.Value().ShapeType() != TopAbs_FACE) continue;
        // Raw orientation for now; build_faces turns it into "same as the face".
        d.faces.push_back({maps.faces.FindIndex(it.Value()),
                           it.Value().Orientation() != TopAbs_REVERSED});
      }
    }
  }
}

void OccModel::build_faces(const TopoDS_Shape& shape, const ShapeMaps& maps) {
  TopTools_IndexedDataMapOfShapeListOfShape f2s;
  TopExp::MapShapesAndAncestors(shape, TopAbs_FACE, TopAbs_SOLID, f2s);
  faces_.resize(maps.faces.Extent());
  for (int i = 1; i <= maps.faces.Extent(); ++i) {
    FaceData& d = faces_[i - 1];
    d.regions = ancestor_tags(f2s, maps.faces(i), maps.solids);
    // Orientation as seen by the first region: its outward normal is the face normal.
    bool forward = maps.faces(i).Orientation() != TopAbs_REVERSED;
    if (!d.regions.empty()) {
      for (const geom::OrientedUse& use : regions_[d.regions.front() - 1].faces) {
        if (use.tag == i) {
          forward = use.forward;
          break;
        }
      }
    }
    d.face = TopoDS::Face(maps.faces(i).Oriented(forward ? TopAbs_FORWARD : TopAbs_REVERSED));
    d.flip_normal = !forward;
    d.surface = BRep_Tool::Surface(d.face);
    while (auto trimmed = Handle(Geom_RectangularTrimmedSurface)::DownCast(d.surface))
      d.surface = trimmed->BasisSurface();
    d.eval = SurfaceEvaluator(d.surface);
    d.type = surface_type(BRepAdaptor_Surface(d.face, false).GetType());
    d.tolerance = BRep_Tool::Tolerance(d.face);

    geom::ParamRange& r = d.range;
    BRepTools::UVBounds(d.face, r.u0, r.u1, r.v0, r.v1);
    double su0, su1, sv0, sv1;
    d.surface->Bounds(su0, su1, sv0, sv1);
    r.periodic_u = d.surface->IsUPeriodic();
    r.periodic_v = d.surface->IsVPeriodic();
    r.period_u = r.periodic_u ? d.surface->UPeriod() : 0;
    r.period_v = r.periodic_v ? d.surface->VPeriod() : 0;
    // A face covering a whole period is searched without bounds in that
    // direction (the parameter wraps); otherwise its UV box bounds the search.
    const auto box_range = [](double lo, double hi, double slo, double shi, bool periodic,
                              double period, double& out_lo, double& out_hi) {
      if (periodic && hi - lo >= period * (1 - 1e-12)) {
        out_lo = -Precision::Infinite();
        out_hi = Precision::Infinite();
        return;
      }
      out_lo = periodic ? lo : std::max(lo, slo);
      out_hi = periodic ? hi : std::min(hi, shi);
    };
    box_range(r.u0, r.u1, su0, su1, r.periodic_u, r.period_u, d.box_u0, d.box_u1);
    box_range(r.v0, r.v1, sv0, sv1, r.periodic_v, r.period_v, d.box_v0, d.box_v1);

    build_face_loops(d, maps);
  }
  // Once every p-curve gap is known: the trimmed-face classifiers, whose ON
  // band is the boundary's uncertainty (face and edge tolerances) in (u, v).
  // Faces in parallel: each writes only its own data and reads its edges'
  // (the grid classification by OCC is a third of a STEP model's load).
  tbb::parallel_for(std::size_t{0}, faces_.size(), [&](std::size_t i) {
    FaceData& d = faces_[i];
    double tol3d = d.tolerance;
    for (const int tag : d.edges) tol3d = std::max(tol3d, edges_[tag - 1].tolerance);
    const GeomAdaptor_Surface adaptor(d.surface);
    const geom::ParamRange& r = d.range;
    const double from_3d = std::min(adaptor.UResolution(tol3d), adaptor.VResolution(tol3d));
    d.uv_tolerance = std::clamp(std::max(from_3d, d.uv_loop_gap), Precision::PConfusion(),
                                1e-3 * std::max(r.u1 - r.u0, r.v1 - r.v0));
    d.classifier = std::make_unique<BRepTopAdaptor_FClass2d>(
        TopoDS::Face(d.face.Oriented(TopAbs_FORWARD)), d.uv_tolerance);
    d.trim = build_trim_classifier(d, edges_);
    build_face_samples(d);
  });
  // Region uses: forward when the region sees the face as its first region does.
  for (RegionData& region : regions_) {
    for (geom::OrientedUse& use : region.faces) {
      const bool stored_forward = !faces_[use.tag - 1].flip_normal;
      use.forward = use.forward == stored_forward;
      region.tolerance = std::max(region.tolerance, faces_[use.tag - 1].tolerance);
      region.box.add(faces_[use.tag - 1].box.min);
      region.box.add(faces_[use.tag - 1].box.max);
    }
  }
}

namespace {

struct EdgeUse {
  TopoDS_Edge edge;  // oriented as used by the face
  int tag = 0;
  bool forward = true;
  Handle(Geom2d_Curve) pcurve;
  gp_Pnt2d start, end;
};

// Orders a wire's uses head to tail by their p-curves' ends in (u, v): the
// fallback when BRepTools_WireExplorer, which chains by vertices, cannot tell
// the uses of a single-vertex wire apart (a torus: two seams, one vertex).
std::vector<EdgeUse> chain_in_uv(std::vector<EdgeUse> uses) {
  std::vector<EdgeUse> chained;
  chained.push_back(uses.front());
  uses.erase(uses.begin());
  while (!uses.empty()) {
    std::size_t best = 0;
    double gap = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < uses.size(); ++k) {
      const double g = chained.back().end.SquareDistance(uses[k].start);
      if (g < gap) {
        gap = g;
        best = k;
      }
    }
    chained.push_back(uses[best]);
    uses.erase(uses.begin() + static_cast<std::ptrdiff_t>(best));
  }
  return chained;
}

// Files often understate an edge's tolerance: its 3D curve and its p-curves
// on the faces disagree by more (up to 1e5 times more in the shared models).
// The model reports the gap it measures, so that "within tolerance of the
// edge" holds for points taken from either representation.
void raise_tolerance_to_pcurve_gap(EdgeData& e, const Geom_Surface& surface,
                                   const Handle(Geom2d_Curve)& pcurve) {
  if (e.degenerate || e.curve.IsNull() || pcurve.IsNull()) return;
  const auto gap_at = [&](double t) {
    const gp_Pnt2d uv = pcurve->Value(t);
    return e.curve->Value(t).Distance(surface.Value(uv.X(), uv.Y()));
  };
  // The gap oscillates between the curves' knots: sample densely, then
  // refine the largest sample's bracket by golden-section search.
  constexpr int kSamples = 100;
  const double h = (e.last - e.first) / kSamples;
  int best = 0;
  double gap = 0;
  for (int k = 0; k <= kSamples; ++k) {
    const double g = gap_at(e.first + h * k);
    if (g > gap) {
      gap = g;
      best = k;
    }
  }
  double a = e.first + h * std::max(best - 1, 0), b = e.first + h * std::min(best + 1, kSamples);
  constexpr double kGolden = 0.6180339887498949;
  for (int iter = 0; iter < 30; ++iter) {
    const double c = b - kGolden * (b - a), d = a + kGolden * (b - a);
    const double gc = gap_at(c), gd = gap_at(d);
    gap = std::max({gap, gc, gd});
    if (gc > gd) {
      b = d;
    } else {
      a = c;
    }
  }
  e.tolerance = std::max(e.tolerance, gap);
}

}  // namespace

void OccModel::build_face_loops(FaceData& d, const ShapeMaps& maps) {
  const TopoDS_Wire outer = BRepTools::OuterWire(d.face);
  const auto make_use = [&](const TopoDS_Edge& e) {
    EdgeUse use;
    use.edge = e;
    use.tag = maps.edges.FindIndex(e);
    use.forward = e.Orientation() != TopAbs_REVERSED;
    double f = 0, l = 0;
    use.pcurve = BRep_Tool::CurveOnSurface(e, d.face, f, l);
    if (!use.pcurve.IsNull()) {
      use.start = use.pcurve->Value(use.forward ? f : l);
      use.end = use.pcurve->Value(use.forward ? l : f);
    }
    return use;
  };
  const auto signature = [](const std::vector<EdgeUse>& uses) {
    std::vector<std::pair<int, bool>> sig;
    for (const EdgeUse& u : uses) sig.emplace_back(u.tag, u.forward);
    std::sort(sig.begin(), sig.end());
    return sig;
  };
  for (TopoDS_Iterator it(d.face); it.More(); it.Next()) {
    if (it.Value().ShapeType() != TopAbs_WIRE) continue;
    const TopoDS_Wire& wire = TopoDS::Wire(it.Value());
    std::vector<EdgeUse> stored, explored;
    for (TopoDS_Iterator e(wire); e.More(); e.Next()) stored.push_back(make_use(TopoDS::Edge(e.Value())));
    if (stored.empty()) continue;
    for (BRepTools_WireExplorer ex(wire, d.face); ex.More(); ex.Next())
      explored.push_back(make_use(TopoDS::Edge(ex.Current().Oriented(ex.Orientation()))));
    std::vector<EdgeUse> uses;
    if (signature(explored) == signature(stored)) {
      uses = std::move(explored);
    } else {
      const bool have_pcurves = std::all_of(stored.begin(), stored.end(),
                                            [](const EdgeUse& u) { return !u.pcurve.IsNull(); });
      uses = have_pcurves ? chain_in_uv(std::move(stored)) : std::move(stored);
    }
    geom::Loop loop;
    loop.outer = wire.IsSame(outer);
    // Gaps between consecutive p-curves: the loop's own uncertainty in (u, v).
    for (std::size_t k = 0; k < uses.size(); ++k) {
      const EdgeUse& a = uses[k];
      const EdgeUse& b = uses[(k + 1) % uses.size()];
      if (!a.pcurve.IsNull() && !b.pcurve.IsNull())
        d.uv_loop_gap = std::max(d.uv_loop_gap, a.end.Distance(b.start));
    }
    for (const EdgeUse& u : uses) {
      raise_tolerance_to_pcurve_gap(edges_[u.tag - 1], *d.surface, u.pcurve);
      loop.edges.push_back({u.tag, u.forward});
      d.pcurves.push_back({u.tag, u.forward, u.pcurve});
      d.edges.push_back(u.tag);
    }
    d.loops.push_back(std::move(loop));
  }
  std::sort(d.edges.begin(), d.edges.end());
  d.edges.erase(std::unique(d.edges.begin(), d.edges.end()), d.edges.end());
}

void OccModel::build_face_samples(FaceData& d) {
  int nu = 13, nv = 13;
  if (d.type == ShapeType::kPlane) nu = nv = 7;
  if (auto bspline = Handle(Geom_BSplineSurface)::DownCast(d.surface)) {
    nu = samples_for_knots(bspline->NbUKnots(), bspline->UDegree());
    nv = samples_for_knots(bspline->NbVKnots(), bspline->VDegree());
  }
  const geom::ParamRange& r = d.range;
  d.grid_step = Vec2((r.u1 - r.u0) / nu, (r.v1 - r.v0) / nv);
  // OCC classifies every other grid point in each direction, which also
  // checks the trim polygons across the face's interior (build_trim_classifier
  // checked them near the loops): a polygon that is wrong there is wrong over
  // an area, and a quarter of the grid sees it. The trim polygons classify the
  // rest, at a fraction of the cost (OCC's classification of the grid was a
  // fifth of a small STEP model's load); all of the grid by OCC once they
  // disagree anywhere.
  const auto param_at = [&](int i, int j) {
    return Vec2(r.u0 + (r.u1 - r.u0) * (i + 0.5) / nu, r.v0 + (r.v1 - r.v0) * (j + 0.5) / nv);
  };
  std::vector<char> inside(static_cast<std::size_t>(nu * nv));
  bool trim_agrees = true;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const Vec2 uv = param_at(i, j);
      const auto fast = d.trim ? trim_face_contains(d, *d.trim, uv) : std::nullopt;
      const bool checked = i % 2 == 0 && j % 2 == 0;
      const bool in = fast && !checked ? *fast : occ_face_contains(d, uv);
      trim_agrees &= !fast || *fast == in;
      inside[static_cast<std::size_t>(i * nv + j)] = in;
    }
  if (!trim_agrees) {
    d.trim.reset();
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j)
        if (i % 2 != 0 || j % 2 != 0) inside[static_cast<std::size_t>(i * nv + j)] = occ_face_contains(d, param_at(i, j));
  }
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      if (!inside[static_cast<std::size_t>(i * nv + j)]) continue;
      const Vec2 uv = param_at(i, j);
      d.sample_params.push_back(uv);
      d.sample_points.push_back(to_vec(d.eval.value(uv.x(), uv.y())));
    }
  d.grid_samples = d.sample_points.size();
  // Box: a face's extreme coordinates are on its boundary (the edges' exact
  // boxes) or at interior critical points, found by ascent from the best
  // grid sample. A plane needs only its edges.
  for (const int tag : d.edges) {
    d.box.add(edges_[tag - 1].box.min);
    d.box.add(edges_[tag - 1].box.max);
  }
  if (d.type != ShapeType::kPlane) {
    for (const Vec3& p : d.sample_points) d.box.add(p);
    add_interior_extremes(d, d.box);
  }
  // Boundary seeds: thin faces may have no interior grid point at all.
  for (const PCurveUse& use : d.pcurves) {
    const EdgeData& e = edges_[use.edge - 1];
    // A pole is a poor seed: Newton cannot move off a singular point.
    if (use.curve.IsNull() || e.degenerate) continue;
    constexpr int kPerEdge = 5;
    for (int k = 0; k < kPerEdge; ++k) {
      const gp_Pnt2d p = use.curve->Value(e.first + (e.last - e.first) * (k + 0.5) / kPerEdge);
      d.sample_params.emplace_back(p.X(), p.Y());
      d.sample_points.push_back(to_vec(d.eval.value(p.X(), p.Y())));
    }
  }
}

// --- lookup ------------------------------------------------------------------

const VertexData& OccModel::vertex_at(int tag) const {
  if (tag < 1 || tag > static_cast<int>(vertices_.size()))
    throw std::out_of_range(fmt::format("no vertex with tag {}", tag));
  return vertices_[tag - 1];
}
const EdgeData& OccModel::edge_at(int tag) const {
  if (tag < 1 || tag > static_cast<int>(edges_.size()))
    throw std::out_of_range(fmt::format("no edge with tag {}", tag));
  return edges_[tag - 1];
}
const FaceData& OccModel::face_at(int tag) const {
  if (tag < 1 || tag > static_cast<int>(faces_.size()))
    throw std::out_of_range(fmt::format("no face with tag {}", tag));
  return faces_[tag - 1];
}
const RegionData& OccModel::region_at(int tag) const {
  if (tag < 1 || tag > static_cast<int>(regions_.size()))
    throw std::out_of_range(fmt::format("no region with tag {}", tag));
  return regions_[tag - 1];
}

// --- topology queries --------------------------------------------------------

int OccModel::count(int dim) const {
  switch (dim) {
    case 0: return static_cast<int>(vertices_.size());
    case 1: return static_cast<int>(edges_.size());
    case 2: return static_cast<int>(faces_.size());
    case 3: return static_cast<int>(regions_.size());
    default: throw std::out_of_range(fmt::format("no entities of dimension {}", dim));
  }
}

geom::ShapeType OccModel::type(geom::EntityRef e) const {
  switch (e.dim) {
    case 0: vertex_at(e.tag); return ShapeType::kPoint;
    case 1: return edge_at(e.tag).type;
    case 2: return face_at(e.tag).type;
    case 3: region_at(e.tag); return ShapeType::kSolid;
    default: throw std::out_of_range(fmt::format("no entities of dimension {}", e.dim));
  }
}

geom::BoundingBox OccModel::bounding_box(geom::EntityRef e) const {
  switch (e.dim) {
    case 0: {
      geom::BoundingBox b;
      b.add(vertex_at(e.tag).point);
      return b;
    }
    case 1: return edge_at(e.tag).box;
    case 2: return face_at(e.tag).box;
    case 3: return region_at(e.tag).box;
    default: throw std::out_of_range(fmt::format("no entities of dimension {}", e.dim));
  }
}

std::vector<geom::OrientedUse> OccModel::region_faces(int region) const {
  return region_at(region).faces;
}

std::vector<geom::Loop> OccModel::face_loops(int face) const { return face_at(face).loops; }

std::array<int, 2> OccModel::edge_vertices(int edge) const { return edge_at(edge).vertices; }

bool OccModel::is_degenerate(int edge) const { return edge_at(edge).degenerate; }

std::vector<int> OccModel::upward(geom::EntityRef e) const {
  switch (e.dim) {
    case 0: return vertex_at(e.tag).edges;
    case 1: return edge_at(e.tag).faces;
    case 2: return face_at(e.tag).regions;
    case 3: region_at(e.tag); return {};
    default: throw std::out_of_range(fmt::format("no entities of dimension {}", e.dim));
  }
}

double OccModel::tolerance(geom::EntityRef e) const {
  switch (e.dim) {
    case 0: return vertex_at(e.tag).tolerance;
    case 1: return edge_at(e.tag).tolerance;
    case 2: return face_at(e.tag).tolerance;
    case 3: return region_at(e.tag).tolerance;
    default: throw std::out_of_range(fmt::format("no entities of dimension {}", e.dim));
  }
}

geom::ParamRange OccModel::param_range(geom::EntityRef e) const {
  switch (e.dim) {
    case 1: return edge_at(e.tag).range;
    case 2: return face_at(e.tag).range;
    default:
      throw std::out_of_range(fmt::format("param_range of a dimension-{} entity", e.dim));
  }
}

Vec3 OccModel::vertex_point(int vertex) const { return vertex_at(vertex).point; }

double OccModel::area(int face) const {
  const FaceData& f = face_at(face);
  return face_areas_[face - 1].get([&] {
    GProp_GProps props;
    BRepGProp::SurfaceProperties(f.face, props);
    return props.Mass();
  });
}

double OccModel::length(int edge) const { return edge_at(edge).length; }

namespace {
MassProperties volume_properties(const TopoDS_Solid& solid) {
  GProp_GProps props;
  BRepGProp::VolumeProperties(solid, props);
  return {props.Mass(), to_vec(props.CentreOfMass())};
}
}  // namespace

double OccModel::volume(int region) const {
  const RegionData& r = region_at(region);
  return region_mass_[region - 1].get([&] { return volume_properties(r.solid); }).mass;
}

Vec3 OccModel::center_of_mass(int region) const {
  const RegionData& r = region_at(region);
  return region_mass_[region - 1].get([&] { return volume_properties(r.solid); }).center;
}

}  // namespace cm::geom_occ::detail

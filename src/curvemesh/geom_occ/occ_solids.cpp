// From the shape as read to a compound of closed, outward-oriented, mutually
// conformal solids: healing, sewing, solid making and the general fuse.
#include <algorithm>
#include <exception>
#include <cmath>
#include <vector>

#include <BRepBuilderAPI_MakeSolid.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepClass3d_SolidClassifier.hxx>
#include <BRep_Builder.hxx>
#include <BRepBndLib.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <Precision.hxx>
#include <ShapeFix_Shape.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/plugin.hpp"

namespace cm::geom_occ::detail {

namespace {

int count_of(const TopoDS_Shape& s, TopAbs_ShapeEnum type) {
  TopTools_IndexedMapOfShape map;
  TopExp::MapShapes(s, type, map);
  return map.Extent();
}

// Faces of `s` that lie in no solid of it.
TopoDS_Compound faces_outside_solids(const TopoDS_Shape& s) {
  TopTools_IndexedMapOfShape all, in_solids;
  TopExp::MapShapes(s, TopAbs_FACE, all);
  for (TopExp_Explorer ex(s, TopAbs_SOLID); ex.More(); ex.Next())
    TopExp::MapShapes(ex.Current(), TopAbs_FACE, in_solids);
  TopoDS_Compound out;
  BRep_Builder builder;
  builder.MakeCompound(out);
  for (int i = 1; i <= all.Extent(); ++i)
    if (!in_solids.Contains(all(i))) builder.Add(out, all(i));
  return out;
}

double largest_vertex_tolerance(const TopoDS_Shape& s) {
  double tol = 0;
  for (TopExp_Explorer ex(s, TopAbs_VERTEX); ex.More(); ex.Next())
    tol = std::max(tol, BRep_Tool::Tolerance(TopoDS::Vertex(ex.Current())));
  return tol;
}

// A free edge of `shell` (bounding one face only, not a seam, not
// degenerate), as "face N (of the shell) near (x, y, z)"; "" if closed.
std::string describe_free_edge(const TopoDS_Shape& shell) {
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(shell, TopAbs_FACE, faces);
  TopTools_IndexedDataMapOfShapeListOfShape e2f;
  TopExp::MapShapesAndAncestors(shell, TopAbs_EDGE, TopAbs_FACE, e2f);
  for (int i = 1; i <= e2f.Extent(); ++i) {
    const TopoDS_Edge& edge = TopoDS::Edge(e2f.FindKey(i));
    if (BRep_Tool::Degenerated(edge) || e2f(i).Extent() != 1) continue;
    const TopoDS_Face& face = TopoDS::Face(e2f(i).First());
    if (BRep_Tool::IsClosed(edge, face)) continue;
    double f = 0, l = 0;
    const Handle(Geom_Curve) c = BRep_Tool::Curve(edge, f, l);
    std::string where;
    if (!c.IsNull()) {
      const gp_Pnt p = c->Value(0.5 * (f + l));
      where = fmt::format(" near ({:.6g}, {:.6g}, {:.6g})", p.X(), p.Y(), p.Z());
    }
    return fmt::format("face {} of {} has a free edge{}", faces.FindIndex(face), faces.Extent(),
                       where);
  }
  return "";
}

// Healing a valid shape may still rebuild wires and renumber entities, so
// valid input is left alone (tags then follow the file); the XSTEP
// translators already heal what they read. The analyzer's parallel mode
// checks sub-shapes on every core.
bool needs_healing(const ReadShape& read, const LoadOptions& options) {
  return options.heal_tolerance > 0 || !BRepCheck_Analyzer(read.shape, Standard_True, Standard_True).IsValid();
}

TopoDS_Shape heal(const ReadShape& read, double tol) {
  ShapeFix_Shape fixer(read.shape);
  fixer.SetPrecision(tol);
  fixer.SetMinTolerance(std::min(tol, Precision::Confusion()));
  fixer.SetMaxTolerance(std::max(tol * 10, 1e-3));
  fixer.Perform();
  return fixer.Shape();
}

std::vector<TopoDS_Solid> solids_of(const TopoDS_Shape& shape) {
  std::vector<TopoDS_Solid> solids;
  for (TopExp_Explorer ex(shape, TopAbs_SOLID); ex.More(); ex.Next()) solids.push_back(TopoDS::Solid(ex.Current()));
  return solids;
}

// Solids of an assembly that nearly touch, or overlap by a hair, are fused
// as if they met exactly when their gap or overlap is under this fraction
// of the model's diagonal. Fused exactly they leave strip faces a millionth
// of the model wide (a cylinder band 3e-6 high on a sink 130 across), far
// below any mesh size there, whose needle triangles no Steiner point can
// recover. Gaps this small are beneath the chord error of any mesh of the
// model.
constexpr double kFuseFuzz = 1e-6;

double diagonal_of(const TopoDS_Shape& shape) {
  Bnd_Box box;
  BRepBndLib::Add(shape, box);
  return box.IsVoid() ? 0 : std::sqrt(box.SquareExtent());
}

std::vector<TopoDS_Solid> sew_into_solids(const TopoDS_Shape& shape, const LoadOptions& options,
                                          double tol, const std::string& source) {
  const int nfaces = count_of(shape, TopAbs_FACE);
  if (nfaces == 0)
    throw GeometryError(fmt::format(
        "{}: no solid and no face: the model holds only {} edge(s) and {} vertex(es)", source,
        count_of(shape, TopAbs_EDGE), count_of(shape, TopAbs_VERTEX)));
  if (!options.sew)
    throw GeometryError(fmt::format("{}: no solid ({} free face(s)) and sewing is disabled",
                                    source, nfaces));
  BRepBuilderAPI_Sewing sewing(tol);
  for (TopExp_Explorer ex(shape, TopAbs_FACE); ex.More(); ex.Next()) sewing.Add(ex.Current());
  sewing.Perform();
  const TopoDS_Shape sewed = sewing.SewedShape();
  std::vector<TopoDS_Solid> solids;
  int shell_index = 0;
  for (TopExp_Explorer ex(sewed, TopAbs_SHELL); ex.More(); ex.Next()) {
    ++shell_index;
    const TopoDS_Shell& shell = TopoDS::Shell(ex.Current());
    if (!BRep_Tool::IsClosed(shell)) {
      throw GeometryError(fmt::format(
          "{}: no solid, and sewing the {} face(s) left shell {} open: {} (try a larger "
          "heal tolerance, now {:g})",
          source, nfaces, shell_index, describe_free_edge(shell), tol));
    }
    BRepBuilderAPI_MakeSolid make(shell);
    if (!make.IsDone())
      throw GeometryError(fmt::format("{}: closed shell {} cannot be made a solid", source,
                                      shell_index));
    solids.push_back(make.Solid());
  }
  // Faces sewing could not attach to any shell stay free.
  int free_faces = 0;
  for (TopExp_Explorer ex(sewed, TopAbs_FACE, TopAbs_SHELL); ex.More(); ex.Next()) ++free_faces;
  if (solids.empty() || free_faces > 0)
    throw GeometryError(fmt::format(
        "{}: no solid, and {} of its {} face(s) could not be sewn into a closed shell", source,
        solids.empty() ? nfaces : free_faces, nfaces));
  return solids;
}

// Makes every solid closed and outward-oriented, naming the culprit otherwise.
void check_and_orient(std::vector<TopoDS_Solid>& solids, const std::string& source) {
  for (std::size_t i = 0; i < solids.size(); ++i) {
    int shell_index = 0;
    for (TopExp_Explorer ex(solids[i], TopAbs_SHELL); ex.More(); ex.Next()) {
      ++shell_index;
      if (!BRep_Tool::IsClosed(ex.Current()))
        throw GeometryError(fmt::format("{}: solid {}: shell {} is not closed: {}", source, i + 1,
                                        shell_index, describe_free_edge(ex.Current())));
    }
  }
  // Inside-out solids see the point at infinity inside. Each solid's
  // classifier reads only its own shape: the solids in parallel.
  tbb::parallel_for(std::size_t{0}, solids.size(), [&](std::size_t i) {
    BRepClass3d_SolidClassifier classifier(solids[i]);
    classifier.PerformInfinitePoint(Precision::Confusion());
    if (classifier.State() == TopAbs_IN) solids[i].Reverse();
  });
}

// One solid as a compound; several, their general fuse by the plugin that
// carries TKBO.
TopoDS_Shape single_or_fused(const std::vector<TopoDS_Solid>& solids, const TopoDS_Shape& shape,
                             const std::string& source) {
  if (solids.size() == 1) {
    TopoDS_Compound result;
    BRep_Builder builder;
    builder.MakeCompound(result);
    builder.Add(result, solids.front());
    return result;
  }
  return plugin(Plugin::kFuse).fuse_solids(solids, kFuseFuzz * diagonal_of(shape), source);
}

}  // namespace

TopoDS_Shape make_conformal_solids(const ReadShape& read, const LoadOptions& options,
                                   const std::string& source) {
  if (read.shape.IsNull()) throw GeometryError(fmt::format("{}: the model is empty", source));
  try {
    const double tol = options.heal_tolerance > 0
                           ? options.heal_tolerance
                           : std::max(1e-7, largest_vertex_tolerance(read.shape));
    // Whether healing is needed, and the orientation of the solids as read,
    // side by side (each reads the shape only): valid input, the usual case,
    // keeps the solids as read, then already oriented.
    std::vector<TopoDS_Solid> as_read = solids_of(read.shape);
    bool healing = false;
    std::exception_ptr orient_error;
    tbb::parallel_invoke([&] { healing = options.heal && needs_healing(read, options); },
                         [&] {
                           try {
                             check_and_orient(as_read, source);
                           } catch (...) {
                             orient_error = std::current_exception();
                           }
                         });
    if (!healing && !as_read.empty()) {
      if (orient_error) std::rethrow_exception(orient_error);
      return single_or_fused(as_read, read.shape, source);
    }
    const TopoDS_Shape shape = healing ? heal(read, tol) : read.shape;

    std::vector<TopoDS_Solid> solids = solids_of(shape);
    // Healing an invalid solid can split it into a few closed pieces and
    // leave the rest of its faces in no solid (a KiCad potentiometer: 3 of
    // its 53 faces kept): those solids would be meshed and the rest of the
    // part silently lost. The faces it left out are sewn into solids too.
    if (const TopoDS_Compound left = faces_outside_solids(shape);
        !solids.empty() && count_of(left, TopAbs_FACE) > count_of(faces_outside_solids(read.shape), TopAbs_FACE)) {
      const std::vector<TopoDS_Solid> sewn = sew_into_solids(left, options, tol, source);
      solids.insert(solids.end(), sewn.begin(), sewn.end());
    }
    if (solids.empty()) solids = sew_into_solids(shape, options, tol, source);
    check_and_orient(solids, source);
    return single_or_fused(solids, shape, source);
  } catch (const Standard_Failure& e) {
    throw GeometryError(fmt::format("{}: OpenCASCADE failed while preparing the solids: {} ({})",
                                    source, e.GetMessageString(), e.DynamicType()->Name()));
  }
}

}  // namespace cm::geom_occ::detail

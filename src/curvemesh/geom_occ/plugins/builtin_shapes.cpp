// Plugin: the built-in models (builtin_catalog.hpp), made with OCC modelling
// operations (TKPrim, TKBool, TKFillet) so tests and examples need no CAD file.
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <map>
#include <string_view>
#include <vector>

#include <BRepAdaptor_Curve.hxx>
#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepFilletAPI_MakeChamfer.hxx>
#include <BRepFilletAPI_MakeFillet.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GeomAPI_PointsToBSplineSurface.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Precision.hxx>
#include <Standard_Failure.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <gp_Ax2.hxx>
#include <gp_Pnt.hxx>
#include <gp_Vec.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/builtin_catalog.hpp"
#include "curvemesh/geom_occ/detail/plugin.hpp"

namespace cm::geom_occ::detail {

namespace {

using Params = std::map<std::string, double, std::less<>>;

Params parse_params(const std::string& spec, const Builtin& b, std::string_view list) {
  Params params;
  for (const auto& [key, value] : b.defaults) params.emplace(std::string(key), value);
  while (!list.empty()) {
    const std::size_t comma = list.find(',');
    const std::string_view item = list.substr(0, comma);
    list = comma == std::string_view::npos ? std::string_view() : list.substr(comma + 1);
    const std::size_t eq = item.find('=');
    if (eq == std::string_view::npos)
      throw InputError(spec, -1, -1, fmt::format("expected key=value, got '{}'", item));
    const std::string_view key = item.substr(0, eq), text = item.substr(eq + 1);
    const auto it = params.find(key);
    if (it == params.end())
      throw InputError(spec, -1, -1,
                       fmt::format("builtin:{} has no parameter '{}' (see --help)", b.name, key));
    double value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value))
      throw InputError(spec, -1, -1,
                       fmt::format("parameter {}: '{}' is not a number", key, text));
    it->second = value;
  }
  return params;
}

void require(bool ok, const std::string& spec, std::string_view what) {
  if (!ok) throw InputError(spec, -1, -1, fmt::format("invalid parameters: {}", what));
}

// Separate solids: make_conformal_solids fuses them into conformal regions
// (the shared face of two blocks, the sphere carved out of the cube).
TopoDS_Shape make_compound(std::initializer_list<TopoDS_Shape> solids) {
  TopoDS_Compound compound;
  BRep_Builder builder;
  builder.MakeCompound(compound);
  for (const TopoDS_Shape& s : solids) builder.Add(compound, s);
  return compound;
}

TopoDS_Shape make_tube(double r, double t, double h) {
  const TopoDS_Shape outer = BRepPrimAPI_MakeCylinder(r, h).Shape();
  // The bore overhangs both ends so the cut leaves no face of zero thickness.
  const gp_Ax2 axis(gp_Pnt(0, 0, -h), gp::DZ());
  return BRepAlgoAPI_Cut(outer, BRepPrimAPI_MakeCylinder(axis, r - t, 3 * h).Shape()).Shape();
}

TopoDS_Shape make_holed_plate(int n, double s, double h, double r) {
  // One boolean with every hole as a tool: n² successive cuts would each
  // rebuild an ever larger shape.
  TopTools_ListOfShape plate, holes;
  plate.Append(BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), s, s, h).Shape());
  const double pitch = s / n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const gp_Ax2 axis(gp_Pnt((i + 0.5) * pitch, (j + 0.5) * pitch, -h), gp::DZ());
      holes.Append(BRepPrimAPI_MakeCylinder(axis, r, 3 * h).Shape());
    }
  BRepAlgoAPI_Cut cut;
  cut.SetArguments(plate);
  cut.SetTools(holes);
  cut.SetRunParallel(false);
  cut.Build();
  if (!cut.IsDone()) throw GeometryError("builtin:holes: the boolean cut failed");
  return cut.Shape();
}

TopoDS_Shape make_sunk_cylinder(double r, double d) {
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 2, 1, 1).Shape();
  const gp_Ax2 axis(gp_Pnt(0.5, 0.5, 1 + r - d), gp::DX());
  return BRepAlgoAPI_Fuse(box, BRepPrimAPI_MakeCylinder(axis, r, 1).Shape()).Shape();
}

TopoDS_Shape make_small_features(double s, double e) {
  const TopoDS_Shape cube = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), s, s, s).Shape();
  // The top edge along x at y = 0: the only edge with both ends at y = 0, z = s.
  BRepFilletAPI_MakeChamfer chamfer(cube);
  TopTools_IndexedMapOfShape edges;
  TopExp::MapShapes(cube, TopAbs_EDGE, edges);
  for (int i = 1; i <= edges.Extent(); ++i) {
    const TopoDS_Edge& edge = TopoDS::Edge(edges(i));
    const gp_Pnt a = BRep_Tool::Pnt(TopExp::FirstVertex(edge));
    const gp_Pnt b = BRep_Tool::Pnt(TopExp::LastVertex(edge));
    if (a.Y() == 0 && b.Y() == 0 && a.Z() == s && b.Z() == s) chamfer.Add(e, edge);
  }
  TopoDS_Shape shape = chamfer.Shape();
  // The cutters overhang the cube so that no face of theirs is coplanar with one of its.
  const TopoDS_Shape step = BRepPrimAPI_MakeBox(gp_Pnt(-e, 2 * s / 3, s - e), s + 2 * e, s / 3 + e, 2 * e).Shape();
  shape = BRepAlgoAPI_Cut(shape, step).Shape();
  const TopoDS_Shape notch = BRepPrimAPI_MakeBox(gp_Pnt(s - e, -e, -e), 2 * e, 2 * e, 2 * e).Shape();
  return BRepAlgoAPI_Cut(shape, notch).Shape();
}

TopoDS_Shape make_part(double s) {
  const double lx = 60 * s, ly = 40 * s, lz = 20 * s;
  TopoDS_Shape block = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), lx, ly, lz).Shape();

  BRepFilletAPI_MakeFillet fillet(block);
  for (TopExp_Explorer ex(block, TopAbs_EDGE); ex.More(); ex.Next()) {
    const BRepAdaptor_Curve curve(TopoDS::Edge(ex.Current()));
    if (curve.GetType() == GeomAbs_Line && curve.Line().Direction().IsParallel(gp::DZ(), 1e-9))
      fillet.Add(6 * s, TopoDS::Edge(ex.Current()));
  }
  TopoDS_Shape part = fillet.Shape();

  // The top becomes a smooth bump: cut away everything above a B-spline
  // surface that overhangs the block on every side.
  constexpr int kNu = 9, kNv = 7;
  TColgp_Array2OfPnt points(1, kNu, 1, kNv);
  for (int i = 1; i <= kNu; ++i) {
    for (int j = 1; j <= kNv; ++j) {
      const double x = -10 * s + (lx + 20 * s) * (i - 1) / (kNu - 1);
      const double y = -10 * s + (ly + 20 * s) * (j - 1) / (kNv - 1);
      const double z = 16 * s + 2.5 * s * std::sin(M_PI * x / (40 * s)) * std::cos(M_PI * y / (30 * s));
      points.SetValue(i, j, gp_Pnt(x, y, z));
    }
  }
  const Handle(Geom_BSplineSurface) surface =
      GeomAPI_PointsToBSplineSurface(points, 3, 5, GeomAbs_C2, 1e-7 * s).Surface();
  const TopoDS_Face sheet = BRepBuilderAPI_MakeFace(surface, Precision::Confusion()).Face();
  const TopoDS_Shape above = BRepPrimAPI_MakePrism(sheet, gp_Vec(0, 0, 30 * s)).Shape();
  part = BRepAlgoAPI_Cut(part, above).Shape();

  for (const double x : {18 * s, 42 * s}) {
    const gp_Ax2 axis(gp_Pnt(x, ly / 2, -5 * s), gp::DZ());
    part = BRepAlgoAPI_Cut(part, BRepPrimAPI_MakeCylinder(axis, 4 * s, 40 * s).Shape()).Shape();
  }
  return part;
}

ReadShape make_builtin(const std::string& spec) {
  std::string_view rest(spec);
  rest.remove_prefix(std::string_view("builtin:").size());
  const std::size_t colon = rest.find(':');
  const std::string_view name = rest.substr(0, colon);
  const std::string_view list = colon == std::string_view::npos ? "" : rest.substr(colon + 1);
  const Builtin* b = nullptr;
  for (const Builtin& candidate : builtins())
    if (candidate.name == name) b = &candidate;
  if (!b) {
    std::string names;
    for (const Builtin& candidate : builtins())
      names += fmt::format("{}{}", names.empty() ? "" : ", ", candidate.name);
    throw InputError(spec, -1, -1, fmt::format("unknown built-in model '{}' ({})", name, names));
  }
  const Params p = parse_params(spec, *b, list);
  const auto positive = [&](const char* key) {
    require(p.at(key) > 0, spec, fmt::format("{} must be > 0", key));
    return p.at(key);
  };
  ReadShape out;
  try {
    if (name == "box") {
      out.shape = BRepPrimAPI_MakeBox(positive("dx"), positive("dy"), positive("dz")).Shape();
    } else if (name == "sphere") {
      out.shape = BRepPrimAPI_MakeSphere(positive("r")).Shape();
    } else if (name == "cylinder") {
      out.shape = BRepPrimAPI_MakeCylinder(positive("r"), positive("h")).Shape();
    } else if (name == "torus") {
      const double major = positive("R"), minor = positive("r");
      require(major > minor, spec, "R must be > r");
      out.shape = BRepPrimAPI_MakeTorus(major, minor).Shape();
    } else if (name == "cone") {
      const double r1 = p.at("r1"), r2 = p.at("r2");
      require(r1 >= 0 && r2 >= 0 && r1 != r2, spec, "r1, r2 must be >= 0 and different");
      out.shape = BRepPrimAPI_MakeCone(r1, r2, positive("h")).Shape();
    } else if (name == "blocks") {
      const double dx1 = positive("dx1"), dx2 = positive("dx2"), dy = positive("dy"), dz = positive("dz");
      const double overlap = p.at("o");
      require(overlap >= 0 && overlap < std::min(dx1, dx2), spec, "the overlap o must be in [0, min(dx1, dx2))");
      out.shape = make_compound({BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), dx1, dy, dz).Shape(),
                                 BRepPrimAPI_MakeBox(gp_Pnt(dx1 - overlap, 0, 0), dx2 + overlap, dy, dz).Shape()});
    } else if (name == "inclusion") {
      const double side = positive("s"), r = positive("r");
      require(2 * r < side, spec, "the sphere (2r) must fit inside the cube (s)");
      const double h = side / 2;
      out.shape = make_compound({BRepPrimAPI_MakeBox(gp_Pnt(-h, -h, -h), side, side, side).Shape(),
                                 BRepPrimAPI_MakeSphere(r).Shape()});
    } else if (name == "thinwall") {
      const double r = positive("r"), t = positive("t");
      require(t < r, spec, "the wall thickness t must be < r");
      out.shape = make_tube(r, t, positive("h"));
    } else if (name == "holes") {
      const double n = p.at("n"), s = positive("s"), r = positive("r");
      require(n >= 1 && n <= 100 && n == std::floor(n), spec, "n must be an integer in [1, 100]");
      require(2 * r < s / n, spec, "the holes (2r) must fit in their cells (s/n)");
      out.shape = make_holed_plate(static_cast<int>(n), s, positive("h"), r);
    } else if (name == "tangent") {
      const double r = positive("r"), d = positive("d");
      require(r < 0.5, spec, "r must be < 0.5 (the cylinder fits on the top face)");
      require(d < r, spec, "d must be < r");
      out.shape = make_sunk_cylinder(r, d);
    } else if (name == "smalledges") {
      const double s = positive("s"), e = positive("e");
      require(e < s / 10, spec, "e must be < s/10");
      // Closer to OCC's confusion tolerance (1e-7) the features are within
      // the model's own tolerance and planar faces stop being exact.
      require(e >= 1e-6, spec, "e must be >= 1e-6 (ten times the modelling tolerance)");
      out.shape = make_small_features(s, e);
    } else {
      out.shape = make_part(positive("scale"));
    }
  } catch (const Standard_Failure& e) {
    throw GeometryError(fmt::format("{}: construction failed: {}", spec, e.GetMessageString()));
  }
  // Parameters at the edge of what a boolean can resolve may give a shape
  // load_model would then heal and renumber, or leave the operands apart (a
  // cylinder sunk 1e-7 stays a second solid touching the box): refuse them
  // here rather than mesh something else than the description says.
  if (!BRepCheck_Analyzer(out.shape).IsValid())
    throw GeometryError(fmt::format("{}: the parameters give an invalid solid", spec));
  const int expected_solids = name == "blocks" || name == "inclusion" ? 2 : 1;
  int solids = 0;
  for (TopExp_Explorer ex(out.shape, TopAbs_SOLID); ex.More(); ex.Next()) ++solids;
  if (solids != expected_solids)
    throw GeometryError(fmt::format("{}: the construction gives {} solids instead of {} (a feature "
                                    "too small for the boolean operation to resolve)",
                                    spec, solids, expected_solids));
  return out;
}

}  // namespace

}  // namespace cm::geom_occ::detail

CM_OCC_PLUGIN(.make_builtin = cm::geom_occ::detail::make_builtin)

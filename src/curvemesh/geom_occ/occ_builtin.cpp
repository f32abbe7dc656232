// Built-in models made with OCC modelling operations, so tests and examples
// need no CAD file. Every dimension is a parameter with a default.
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <map>
#include <string_view>
#include <vector>

#include <BRepAdaptor_Curve.hxx>
#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepFilletAPI_MakeFillet.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRep_Builder.hxx>
#include <GeomAPI_PointsToBSplineSurface.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Precision.hxx>
#include <Standard_Failure.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <gp_Ax2.hxx>
#include <gp_Pnt.hxx>
#include <gp_Vec.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/occ_shapes.hpp"

namespace cm::geom_occ::detail {

namespace {

using Params = std::map<std::string, double, std::less<>>;

struct Builtin {
  std::string_view name;
  std::string_view description;
  std::vector<std::pair<std::string_view, double>> defaults;
};

const std::vector<Builtin>& builtins() {
  static const std::vector<Builtin> kBuiltins = {
      {"box", "box [0,dx] x [0,dy] x [0,dz]", {{"dx", 1}, {"dy", 1}, {"dz", 1}}},
      {"sphere", "sphere of radius r centred at the origin", {{"r", 1}}},
      {"cylinder", "cylinder of radius r and height h on the z axis from z = 0",
       {{"r", 1}, {"h", 2}}},
      {"torus", "torus about the z axis: major radius R > minor radius r",
       {{"R", 2}, {"r", 0.5}}},
      {"cone", "truncated cone on the z axis: radius r1 at z = 0, r2 at z = h (one may be 0)",
       {{"r1", 1}, {"r2", 0.5}, {"h", 2}}},
      {"part",
       "mechanical part: a 60x40x20 block (times scale) with filleted vertical edges, two "
       "through holes and a freeform B-spline top face",
       {{"scale", 1}}},
      {"blocks",
       "two regions sharing the face x = dx1: boxes [0,dx1] x [0,dy] x [0,dz] and "
       "[dx1,dx1+dx2] x [0,dy] x [0,dz]",
       {{"dx1", 1}, {"dx2", 1}, {"dy", 1}, {"dz", 1}}},
      {"inclusion",
       "two regions: a sphere of radius r inside the cube [-s/2,s/2]^3, and the rest of the cube",
       {{"s", 2}, {"r", 0.5}}},
  };
  return kBuiltins;
}

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

}  // namespace

ReadShape make_builtin(const std::string& spec) {
  std::string_view rest(spec);
  rest.remove_prefix(std::string_view("builtin:").size());
  const std::size_t colon = rest.find(':');
  const std::string_view name = rest.substr(0, colon);
  const std::string_view list = colon == std::string_view::npos ? "" : rest.substr(colon + 1);
  const Builtin* b = nullptr;
  for (const Builtin& candidate : builtins())
    if (candidate.name == name) b = &candidate;
  if (!b)
    throw InputError(spec, -1, -1,
                     fmt::format("unknown built-in model '{}' (box, sphere, cylinder, torus, "
                                 "cone, part, blocks, inclusion)",
                                 name));
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
      out.shape = make_compound({BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), dx1, dy, dz).Shape(),
                                 BRepPrimAPI_MakeBox(gp_Pnt(dx1, 0, 0), dx2, dy, dz).Shape()});
    } else if (name == "inclusion") {
      const double side = positive("s"), r = positive("r");
      require(2 * r < side, spec, "the sphere (2r) must fit inside the cube (s)");
      const double h = side / 2;
      out.shape = make_compound({BRepPrimAPI_MakeBox(gp_Pnt(-h, -h, -h), side, side, side).Shape(),
                                 BRepPrimAPI_MakeSphere(r).Shape()});
    } else {
      out.shape = make_part(positive("scale"));
    }
  } catch (const Standard_Failure& e) {
    throw GeometryError(fmt::format("{}: construction failed: {}", spec, e.GetMessageString()));
  }
  return out;
}

std::string builtin_help_text() {
  std::string text;
  for (const Builtin& b : builtins()) {
    std::string params;
    for (const auto& [key, value] : b.defaults)
      params += fmt::format("{}{}={:g}", params.empty() ? "" : ",", key, value);
    text += fmt::format("  builtin:{}:{}\n      {}\n", b.name, params, b.description);
  }
  return text;
}

}  // namespace cm::geom_occ::detail

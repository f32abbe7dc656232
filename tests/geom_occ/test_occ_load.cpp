// Loading the shared CAD models: entity counts, tags, units, mass properties
// and topology checked against an independent OpenCASCADE reading.
#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include <BRepAdaptor_Surface.hxx>
#include <BRepBndLib.hxx>
#include <BRepGProp.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>

#include "curvemesh/geom_occ/load.hpp"
#include "occ_reference.hpp"

namespace cm::geom_occ {
namespace {

using geom::EntityRef;

class ModelFile : public ::testing::TestWithParam<std::string> {};

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = test::base_name(info.param);
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

double mass(const TopoDS_Shape& s, int dim) {
  GProp_GProps props;
  if (dim == 1) BRepGProp::LinearProperties(s, props);
  if (dim == 2) BRepGProp::SurfaceProperties(s, props);
  if (dim == 3) BRepGProp::VolumeProperties(s, props);
  return props.Mass();
}

const std::map<std::string, std::string> kExpectedUnits = {
    {"1385_Laufrad_1000.stp", "mm"}, {"917_fusee.stp", "m"},
    {"918_pump_carter_sup_21_03_2006.stp", "mm"}, {"SampleCrankshaft4A.stp", "inch"},
    {"Zylkopf.stp", "mm"}, {"metallmeister_gear.step", "mm"}, {"t20_data.step", "mm"},
    {"Torus_1.brep", ""}, {"dlr_f6.brep", ""}, {"full_sphere.brep", ""}, {"ring.brep", ""},
};

TEST(OccModelFiles, AllElevenModelsArePresent) { EXPECT_EQ(test::model_files().size(), 11u); }

TEST_P(ModelFile, CountsTagsUnitsAndMassPropertiesMatchAnIndependentReading) {
  const std::string path = GetParam();
  const auto start = std::chrono::steady_clock::now();
  const auto model = load_model(path);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("[load] %s %.3f s\n", test::base_name(path).c_str(), seconds);
  const test::Reference ref = test::read_reference(path);

  ASSERT_TRUE(kExpectedUnits.count(test::base_name(path)));
  EXPECT_EQ(model->units(), kExpectedUnits.at(test::base_name(path)));
  const double f = test::mm_per_unit(model->units());  // the reference is in mm

  ASSERT_EQ(model->count(0), ref.vertices.Extent());
  ASSERT_EQ(model->count(1), ref.edges.Extent());
  ASSERT_EQ(model->count(2), ref.faces.Extent());
  ASSERT_EQ(model->count(3), ref.solids_map.Extent());
  const double diag = model->bounding_box().diagonal();

  // Same tag, same entity: positions, lengths, areas, volumes.
  for (int v = 1; v <= model->count(0); ++v) {
    const gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(ref.vertices(v)));
    EXPECT_NEAR((model->vertex_point(v) * f - Vec3(p.X(), p.Y(), p.Z())).norm(), 0, 1e-9 * diag * f)
        << "vertex " << v;
  }
  // Non-mm files: the reference is translated in mm, where OCC's minimal
  // tolerance (1e-7 system units) differs, so its healing places vertices
  // differently within the file's uncertainty. Differences are then bounded
  // by the entities' tolerances; mm files must agree to round-off.
  const bool same_units = f == 1;
  double model_tolerance = 0;  // the largest vertex tolerance, in mm
  for (int v = 1; v <= ref.vertices.Extent(); ++v)
    model_tolerance = std::max(model_tolerance, BRep_Tool::Tolerance(TopoDS::Vertex(ref.vertices(v))));
  std::vector<double> edge_lengths(model->count(1) + 1);
  for (int e = 1; e <= model->count(1); ++e) {
    EXPECT_EQ(model->is_degenerate(e), BRep_Tool::Degenerated(TopoDS::Edge(ref.edges(e))));
    const double expected = edge_lengths[e] = mass(ref.edges(e), 1);
    const double slack = same_units ? 0 : 2 * model_tolerance;
    EXPECT_NEAR(model->length(e) * f, expected, 1e-7 * expected + 1e-9 * diag * f + slack)
        << "edge " << e;
  }
  std::map<geom::ShapeType, int> types, ref_types;
  double total_area = 0;
  for (int t = 1; t <= model->count(2); ++t) {
    const double expected = mass(ref.faces(t), 2);
    total_area += expected;
    double perimeter = 0;
    for (const geom::Loop& loop : model->face_loops(t))
      for (const geom::OrientedUse& use : loop.edges) perimeter += edge_lengths[use.tag];
    const double slack = same_units ? 0 : perimeter * model_tolerance;
    EXPECT_NEAR(model->area(t) * f * f, expected, 1e-6 * expected + slack) << "face " << t;
    ++types[model->type({2, t})];
    switch (BRepAdaptor_Surface(TopoDS::Face(ref.faces(t))).GetType()) {
      case GeomAbs_Plane: ++ref_types[geom::ShapeType::kPlane]; break;
      case GeomAbs_Cylinder: ++ref_types[geom::ShapeType::kCylinder]; break;
      case GeomAbs_Torus: ++ref_types[geom::ShapeType::kTorus]; break;
      case GeomAbs_BSplineSurface: ++ref_types[geom::ShapeType::kBSplineSurface]; break;
      default: ++ref_types[model->type({2, t})]; break;  // only the common ones are re-derived
    }
  }
  EXPECT_EQ(types, ref_types);
  for (int r = 1; r <= model->count(3); ++r) {
    const double expected = mass(ref.solids_map(r), 3);
    const double slack = same_units ? 0 : total_area * model_tolerance;
    EXPECT_GT(model->volume(r), 0);
    EXPECT_NEAR(model->volume(r) * f * f * f, expected, 1e-6 * std::abs(expected) + slack)
        << "region " << r;
  }

  // Face boxes enclose OCC's optimal box and are not much larger (a sample
  // of faces: the optimal box is what load_model avoids computing).
  const int step = std::max(1, model->count(2) / 12);
  for (int t = 1; t <= model->count(2); t += step) {
    Bnd_Box b;
    BRepBndLib::AddOptimal(ref.faces(t), b, false, false);
    double x0, y0, z0, x1, y1, z1;
    b.Get(x0, y0, z0, x1, y1, z1);
    const geom::BoundingBox box = model->bounding_box({2, t});
    const Vec3 lo = box.min * f, hi = box.max * f;
    const double slack = 1e-6 * (Vec3(x1, y1, z1) - Vec3(x0, y0, z0)).norm() + 1e-9 * diag * f;
    EXPECT_LE(lo.x(), x0 + slack);
    EXPECT_LE(lo.y(), y0 + slack);
    EXPECT_LE(lo.z(), z0 + slack);
    EXPECT_GE(hi.x(), x1 - slack);
    EXPECT_GE(hi.y(), y1 - slack);
    EXPECT_GE(hi.z(), z1 - slack);
    EXPECT_LE((lo - Vec3(x0, y0, z0)).norm() + (hi - Vec3(x1, y1, z1)).norm(),
              0.01 * box.diagonal() * f + 1e-6 * diag * f)
        << "face " << t << " box much larger than the optimal one";
  }
}

TEST_P(ModelFile, TopologyIsConsistent) {
  const auto model = load_model(GetParam());
  for (int e = 1; e <= model->count(1); ++e) {
    for (const int v : model->edge_vertices(e)) {
      if (v == 0) continue;
      const auto up = model->upward({0, v});
      EXPECT_TRUE(std::count(up.begin(), up.end(), e)) << "vertex " << v << " misses edge " << e;
    }
    EXPECT_EQ(model->type({1, e}) == geom::ShapeType::kPoint, model->is_degenerate(e));
    EXPECT_FALSE(model->upward({1, e}).empty()) << "edge " << e << " bounds no face";
  }
  for (int f = 1; f <= model->count(2); ++f) {
    const auto loops = model->face_loops(f);
    ASSERT_FALSE(loops.empty());
    EXPECT_EQ(std::count_if(loops.begin(), loops.end(), [](const geom::Loop& l) { return l.outer; }), 1)
        << "face " << f;
    std::map<int, std::vector<bool>> uses;
    for (const geom::Loop& loop : loops) {
      const std::size_t n = loop.edges.size();
      for (std::size_t i = 0; i < n; ++i) {
        const geom::OrientedUse& a = loop.edges[i];
        const geom::OrientedUse& b = loop.edges[(i + 1) % n];
        uses[a.tag].push_back(a.forward);
        const auto va = model->edge_vertices(a.tag), vb = model->edge_vertices(b.tag);
        const int a_end = a.forward ? va[1] : va[0];
        const int b_start = b.forward ? vb[0] : vb[1];
        EXPECT_EQ(a_end, b_start) << "face " << f << ": loop breaks between edges " << a.tag
                                  << " and " << b.tag;
        const auto up = model->upward({1, a.tag});
        EXPECT_TRUE(std::count(up.begin(), up.end(), f));
      }
    }
    for (const auto& [edge, dirs] : uses) {
      // A seam is used twice, once each way.
      ASSERT_LE(dirs.size(), 2u) << "face " << f << " edge " << edge;
      if (dirs.size() == 2) {
        EXPECT_NE(dirs[0], dirs[1]) << "face " << f << " seam " << edge;
      }
    }
    const auto regions = model->upward({2, f});
    ASSERT_GE(regions.size(), 1u);
    ASSERT_LE(regions.size(), 2u);
    std::vector<bool> orientation;
    for (const int r : regions) {
      int found = 0;
      for (const geom::OrientedUse& use : model->region_faces(r)) {
        if (use.tag != f) continue;
        ++found;
        orientation.push_back(use.forward);
      }
      EXPECT_EQ(found, 1) << "face " << f << " in region " << r;
    }
    EXPECT_TRUE(orientation[0]) << "the first region defines the face orientation";
    if (orientation.size() == 2) {
      EXPECT_FALSE(orientation[1]) << "interface face " << f;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Models, ModelFile, ::testing::ValuesIn(test::model_files()), test_name);

TEST(OccModelFiles, RingSolidsShareTheirInterfaceFaces) {
  const std::string path = std::string(CM_SHARED_DIR) + "/models/ring.brep";
  const test::Reference ref = test::read_reference(path);
  // As read: 2 solids, 13 faces, the 6 faces of the small ring stored twice
  // (once per solid). After the general fuse they are one face each: 7 faces.
  TopTools_IndexedMapOfShape raw_faces, raw_solids;
  TopExp::MapShapes(ref.raw, TopAbs_FACE, raw_faces);
  TopExp::MapShapes(ref.raw, TopAbs_SOLID, raw_solids);
  ASSERT_EQ(raw_faces.Extent(), 13);
  const auto model = load_model(path);
  ASSERT_EQ(model->count(3), 2);
  ASSERT_EQ(model->count(2), 13 - 6);
  std::set<int> shared;
  for (int f = 1; f <= model->count(2); ++f)
    if (model->upward({2, f}) == std::vector<int>{1, 2}) shared.insert(f);
  EXPECT_EQ(shared.size(), 6u);
  for (const int r : {1, 2}) {
    std::set<int> faces;
    for (const geom::OrientedUse& use : model->region_faces(r)) faces.insert(use.tag);
    for (const int f : shared) EXPECT_TRUE(faces.count(f)) << "region " << r << " lacks face " << f;
  }
  EXPECT_EQ(model->region_faces(1).size() + model->region_faces(2).size(), 6u + 7u);
  double raw_volume = 0;
  for (int s = 1; s <= raw_solids.Extent(); ++s) raw_volume += mass(raw_solids(s), 3);
  EXPECT_NEAR(model->volume(1) + model->volume(2), raw_volume, 1e-6 * raw_volume);
}

TEST(OccModelFiles, DlrF6DropsItsFreeFace) {
  const std::string path = std::string(CM_SHARED_DIR) + "/models/dlr_f6.brep";
  const test::Reference ref = test::read_reference(path);
  TopTools_IndexedMapOfShape raw_faces;
  TopExp::MapShapes(ref.raw, TopAbs_FACE, raw_faces);
  EXPECT_EQ(raw_faces.Extent(), 130);  // 129 bound the fluid solid, 1 floats free
  EXPECT_EQ(load_model(path)->count(2), 129);
}

}  // namespace
}  // namespace cm::geom_occ

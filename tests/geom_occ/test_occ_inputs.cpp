// load_model on bad input (each a typed error with a clear message), on
// synthetic files exercising sewing, the general fuse, IGES and units, and
// on the built-in shapes.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <STEPControl_Controller.hxx>
#include <STEPControl_Writer.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Shell.hxx>
#include <gp_Pnt.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/load.hpp"

namespace cm::geom_occ {
namespace {

namespace fs = std::filesystem;

class OccInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("cm_occ_inputs_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write_text(const std::string& name, const std::string& text) const {
    std::ofstream(path(name), std::ios::binary) << text;
    return path(name);
  }
  std::string write_brep(const std::string& name, const TopoDS_Shape& shape) const {
    EXPECT_TRUE(BRepTools::Write(shape, path(name).c_str()));
    return path(name);
  }
  std::string write_step(const std::string& name, const TopoDS_Shape& shape,
                         STEPControl_StepModelType mode = STEPControl_AsIs) const {
    STEPControl_Writer writer;
    EXPECT_EQ(writer.Transfer(shape, mode), IFSelect_RetDone);
    EXPECT_EQ(writer.Write(path(name).c_str()), IFSelect_RetDone);
    return path(name);
  }

  fs::path dir_;
};

// The error's message must contain `needle` (the clear-message part).
template <class Error>
void expect_error(const std::string& model, const std::string& needle, const LoadOptions& options = {}) {
  try {
    load_model(model, options);
    ADD_FAILURE() << model << ": loaded, expected an error containing '" << needle << "'";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << "message '" << e.what() << "' lacks '" << needle << "'";
  } catch (const std::exception& e) {
    ADD_FAILURE() << model << ": wrong exception type: " << e.what();
  }
}

TopoDS_Shape unit_box() { return BRepPrimAPI_MakeBox(1, 1, 1).Shape(); }

TEST_F(OccInputs, MissingEmptyAndMisnamedFilesAreInputErrors) {
  expect_error<InputError>(path("absent.step"), "no such file");
  expect_error<InputError>(write_text("empty.step", ""), "empty file");
  expect_error<InputError>(write_text("notes.step", "just some text\nnot a model\n"),
                           "not a STEP file");
  expect_error<InputError>(write_text("garbage.step", "ISO-10303-21;\nHEADER;\n#1 = ((( garbage\n"),
                           "STEP parser rejected");
  expect_error<InputError>(write_text("model.txt", "x"), "unknown model file extension");
  fs::create_directories(path("folder.step"));
  expect_error<InputError>(path("folder.step"), "is a directory");
  // B-rep content named .step and STEP content named .brep.
  const std::string brep = write_brep("box.brep", unit_box());
  fs::copy_file(brep, path("box_as.step"));
  expect_error<InputError>(path("box_as.step"), "not a STEP file");
  const std::string step = write_step("box.step", unit_box());
  fs::copy_file(step, path("box_as.brep"));
  expect_error<InputError>(path("box_as.brep"), "not an OpenCASCADE B-rep file");
  expect_error<InputError>(write_text("text.iges", "hello\n"), "IGES");
}

TEST_F(OccInputs, TruncatedBrepIsAnError) {
  const std::string ring = std::string(CM_SHARED_DIR) + "/models/ring.brep";
  std::ifstream in(ring, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const double fraction : {0.3, 0.6, 0.95}) {
    const std::string name = "cut" + std::to_string(static_cast<int>(fraction * 100)) + ".brep";
    write_text(name, text.substr(0, static_cast<std::size_t>(text.size() * fraction)));
    try {
      load_model(path(name));
      ADD_FAILURE() << name << " loaded";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    } catch (const GeometryError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

TEST_F(OccInputs, StepWithoutSolidOrFaceIsAGeometryError) {
  const TopoDS_Edge edge = BRepBuilderAPI_MakeEdge(gp_Pnt(0, 0, 0), gp_Pnt(1, 2, 3)).Edge();
  expect_error<GeometryError>(write_step("wire.step", edge), "no solid");
}

TEST_F(OccInputs, OpenShellIsAGeometryErrorNamingAFreeEdge) {
  // A box with its top face removed: five faces that sew into an open shell.
  BRep_Builder builder;
  TopoDS_Compound faces;
  builder.MakeCompound(faces);
  int n = 0;
  for (TopExp_Explorer ex(unit_box(), TopAbs_FACE); ex.More(); ex.Next())
    if (n++ != 5) builder.Add(faces, ex.Current());
  expect_error<GeometryError>(write_brep("open.brep", faces), "free edge");
}

TEST_F(OccInputs, LooseFacesAreSewnIntoASolid) {
  BRep_Builder builder;
  TopoDS_Compound faces;
  builder.MakeCompound(faces);
  // Copies, so that no edge is shared and sewing has to find the neighbours.
  for (TopExp_Explorer ex(BRepPrimAPI_MakeBox(2, 3, 4).Shape(), TopAbs_FACE); ex.More(); ex.Next()) {
    const std::string name = path("face.brep");
    BRepTools::Write(ex.Current(), name.c_str());
    TopoDS_Shape copy;
    BRepTools::Read(copy, name.c_str(), builder);
    builder.Add(faces, copy);
  }
  const std::string file = write_brep("faces.brep", faces);
  const auto model = load_model(file);
  ASSERT_EQ(model->count(3), 1);
  EXPECT_EQ(model->count(2), 6);
  EXPECT_EQ(model->count(1), 12);
  EXPECT_EQ(model->count(0), 8);
  EXPECT_NEAR(model->volume(1), 24, 1e-9);
  LoadOptions no_sew;
  no_sew.sew = false;
  expect_error<GeometryError>(file, "sewing is disabled", no_sew);
}

TEST_F(OccInputs, TouchingSolidsShareOneInterfaceFace) {
  BRep_Builder builder;
  TopoDS_Compound two;
  builder.MakeCompound(two);
  builder.Add(two, BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 1, 1, 1).Shape());
  builder.Add(two, BRepPrimAPI_MakeBox(gp_Pnt(1, 0, 0), 1, 1, 1).Shape());
  const auto model = load_model(write_brep("two.brep", two));
  ASSERT_EQ(model->count(3), 2);
  EXPECT_EQ(model->count(2), 11);
  EXPECT_EQ(model->count(1), 20);
  EXPECT_EQ(model->count(0), 12);
  int shared = 0;
  for (int f = 1; f <= model->count(2); ++f) {
    if (model->upward({2, f}) != std::vector<int>{1, 2}) continue;
    ++shared;
    EXPECT_NEAR(model->area(f), 1, 1e-12);
    // Outward of region 1 (+x), so inward for region 2.
    const geom::ParamRange r = model->param_range({2, f});
    const Vec2 mid(0.5 * (r.u0 + r.u1), 0.5 * (r.v0 + r.v1));
    EXPECT_NEAR(model->face_normal(f, mid).x(), 1, 1e-12);
  }
  EXPECT_EQ(shared, 1);
  EXPECT_NEAR(model->volume(1) + model->volume(2), 2, 1e-12);
}

// Solids stored inside out (their faces' normals pointing in) are turned
// outward, each on its own, alone or among others that are not.
TEST_F(OccInputs, InsideOutSolidsAreTurnedOutward) {
  const TopoDS_Shape inside_out = BRepPrimAPI_MakeBox(1, 1, 1).Shape().Reversed();
  const auto one = load_model(write_brep("one.brep", inside_out));
  ASSERT_EQ(one->count(3), 1);
  EXPECT_NEAR(one->volume(1), 1, 1e-12);

  BRep_Builder builder;
  TopoDS_Compound three;
  builder.MakeCompound(three);
  builder.Add(three, BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 1, 1, 1).Shape().Reversed());
  builder.Add(three, BRepPrimAPI_MakeBox(gp_Pnt(2, 0, 0), 1, 1, 1).Shape());
  builder.Add(three, BRepPrimAPI_MakeBox(gp_Pnt(4, 0, 0), 1, 1, 1).Shape().Reversed());
  const auto model = load_model(write_brep("three.brep", three));
  ASSERT_EQ(model->count(3), 3);
  for (int r = 1; r <= 3; ++r) EXPECT_NEAR(model->volume(r), 1, 1e-12) << "region " << r;
  // Every face's normal points away from its region's centre.
  for (int f = 1; f <= model->count(2); ++f) {
    const int r = model->upward({2, f}).front();
    const geom::ParamRange pr = model->param_range({2, f});
    const Vec2 mid(0.5 * (pr.u0 + pr.u1), 0.5 * (pr.v0 + pr.v1));
    EXPECT_GT(model->face_normal(f, mid).dot(model->face_point(f, mid) - model->center_of_mass(r)), 0) << "face " << f;
  }
}

TEST_F(OccInputs, OverlappingSolidsSplitIntoTheirPieces) {
  BRep_Builder builder;
  TopoDS_Compound two;
  builder.MakeCompound(two);
  builder.Add(two, BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 2, 1, 1).Shape());
  builder.Add(two, BRepPrimAPI_MakeBox(gp_Pnt(1, 0, 0), 2, 1, 1).Shape());
  const auto model = load_model(write_brep("overlap.brep", two));
  ASSERT_EQ(model->count(3), 3);
  for (int r = 1; r <= 3; ++r) EXPECT_NEAR(model->volume(r), 1, 1e-12);
}

TEST_F(OccInputs, IgesInInchesKeepsItsUnit) {
  IGESControl_Controller::Init();
  // 25.4 mm in OCC's modelling unit: 1 inch in the file.
  IGESControl_Writer writer("IN", 1);
  writer.AddShape(BRepPrimAPI_MakeBox(25.4, 50.8, 76.2).Shape());
  writer.ComputeModel();
  ASSERT_TRUE(writer.Write(path("box.igs").c_str()));
  const auto model = load_model(path("box.igs"));
  EXPECT_EQ(model->units(), "inch");
  ASSERT_EQ(model->count(3), 1);
  EXPECT_NEAR(model->volume(1), 6, 1e-6);
  const geom::BoundingBox box = model->bounding_box();
  EXPECT_NEAR(box.size().x(), 1, 1e-6);
  EXPECT_NEAR(box.size().z(), 3, 1e-6);
}

TEST_F(OccInputs, StepInMetresKeepsItsUnit) {
  STEPControl_Controller::Init();  // registers the statics before they are set
  const std::string saved = Interface_Static::CVal("write.step.unit");
  Interface_Static::SetCVal("write.step.unit", "M");
  STEPControl_Writer writer;  // reads the unit when it makes its model
  EXPECT_EQ(writer.Transfer(BRepPrimAPI_MakeBox(1000, 2000, 500).Shape(), STEPControl_AsIs),
            IFSelect_RetDone);
  EXPECT_EQ(writer.Write(path("box_m.step").c_str()), IFSelect_RetDone);
  Interface_Static::SetCVal("write.step.unit", saved.c_str());
  const auto model = load_model(path("box_m.step"));
  EXPECT_EQ(model->units(), "m");
  EXPECT_NEAR(model->volume(1), 1, 1e-9);
  EXPECT_NEAR(model->bounding_box().size().y(), 2, 1e-6);
}

TEST(OccBuiltins, PrimitivesHaveExactCountsAndVolumes) {
  const auto box = load_model("builtin:box:dx=2,dy=3,dz=4");
  EXPECT_EQ(box->count(0), 8);
  EXPECT_EQ(box->count(1), 12);
  EXPECT_EQ(box->count(2), 6);
  EXPECT_EQ(box->count(3), 1);
  EXPECT_NEAR(box->volume(1), 24, 1e-12);
  EXPECT_EQ(box->units(), "");
  const auto sphere = load_model("builtin:sphere:r=2");
  EXPECT_NEAR(sphere->volume(1), 4.0 / 3 * M_PI * 8, 1e-9);
  EXPECT_EQ(sphere->type({2, 1}), geom::ShapeType::kSphere);
  int degenerate = 0;
  for (int e = 1; e <= sphere->count(1); ++e) degenerate += sphere->is_degenerate(e);
  EXPECT_EQ(degenerate, 2);  // the poles
  EXPECT_NEAR(load_model("builtin:cylinder:r=1.5,h=3")->volume(1), M_PI * 2.25 * 3, 1e-9);
  EXPECT_NEAR(load_model("builtin:torus:R=2,r=0.5")->volume(1), 2 * M_PI * M_PI * 2 * 0.25, 1e-9);
  EXPECT_NEAR(load_model("builtin:cone:r1=1,r2=0.5,h=2")->volume(1),
              M_PI * 2 * (1 + 0.5 + 0.25) / 3, 1e-9);
  EXPECT_NEAR(load_model("builtin:cone:r1=1,r2=0,h=3")->volume(1), M_PI, 1e-9);
}

TEST(OccBuiltins, PartIsAFilletedBlockWithTwoHolesAndAFreeformTop) {
  const auto part = load_model("builtin:part");
  ASSERT_EQ(part->count(3), 1);
  std::multiset<geom::ShapeType> types;
  for (int f = 1; f <= part->count(2); ++f) types.insert(part->type({2, f}));
  EXPECT_EQ(types.count(geom::ShapeType::kBSplineSurface), 1u);
  EXPECT_EQ(types.count(geom::ShapeType::kCylinder), 4u + 2u);  // fillets + holes
  EXPECT_EQ(types.count(geom::ShapeType::kPlane), 5u);          // bottom + 4 sides
  const geom::BoundingBox b = part->bounding_box();
  EXPECT_NEAR(b.min.x(), 0, 1e-6);
  EXPECT_NEAR(b.max.x(), 60, 1e-6);
  EXPECT_NEAR(b.max.y(), 40, 1e-6);
  EXPECT_GT(b.max.z(), 16);
  EXPECT_LT(b.max.z(), 19);
  // Deterministic: a second build is the same model.
  const auto again = load_model("builtin:part");
  for (int d = 0; d <= 3; ++d) EXPECT_EQ(again->count(d), part->count(d));
  EXPECT_EQ(again->volume(1), part->volume(1));
  const auto scaled = load_model("builtin:part:scale=0.5");
  EXPECT_NEAR(scaled->volume(1), part->volume(1) / 8, 1e-6 * part->volume(1));
}

TEST(OccBuiltins, BlocksAndInclusionAreConformalTwoRegionModels) {
  const auto blocks = load_model("builtin:blocks:dx1=1,dx2=2");
  ASSERT_EQ(blocks->count(3), 2);
  EXPECT_EQ(blocks->count(2), 11);  // the face x = 1 once
  std::multiset<double> volumes{blocks->volume(1), blocks->volume(2)};
  EXPECT_NEAR(*volumes.begin(), 1, 1e-12);
  EXPECT_NEAR(*volumes.rbegin(), 2, 1e-12);
  int shared = 0;
  for (int f = 1; f <= blocks->count(2); ++f) shared += blocks->upward({2, f}).size() == 2;
  EXPECT_EQ(shared, 1);

  const auto inclusion = load_model("builtin:inclusion:s=2,r=0.5");
  ASSERT_EQ(inclusion->count(3), 2);
  const double ball = 4.0 / 3 * M_PI * 0.125;
  volumes = {inclusion->volume(1), inclusion->volume(2)};
  EXPECT_NEAR(*volumes.begin(), ball, 1e-9);
  EXPECT_NEAR(*volumes.rbegin(), 8 - ball, 1e-9);
  // The sphere's face bounds both regions; the cube's six only the outer one.
  int sphere_faces = 0;
  for (int f = 1; f <= inclusion->count(2); ++f)
    if (inclusion->type({2, f}) == geom::ShapeType::kSphere) {
      ++sphere_faces;
      EXPECT_EQ(inclusion->upward({2, f}), (std::vector<int>{1, 2}));
    }
  EXPECT_GE(sphere_faces, 1);
  expect_error<InputError>("builtin:inclusion:s=1,r=0.5", "must fit inside");
}

TEST(OccBuiltins, QueriesOnMissingEntitiesThrow) {
  const auto box = load_model("builtin:box");
  EXPECT_THROW(box->type({2, 7}), std::out_of_range);
  EXPECT_THROW(box->type({2, 0}), std::out_of_range);
  EXPECT_THROW(box->face_loops(0), std::out_of_range);
  EXPECT_THROW(box->upward({1, 13}), std::out_of_range);
  EXPECT_THROW(box->count(4), std::out_of_range);
  EXPECT_THROW(box->closest_point({3, 1}, Vec3::Zero()), std::out_of_range);
  // An edge of the box that does not bound face 1.
  int foreign = 0;
  for (int e = 1; e <= box->count(1) && foreign == 0; ++e) {
    const auto up = box->upward({1, e});
    if (std::find(up.begin(), up.end(), 1) == up.end()) foreign = e;
  }
  ASSERT_GT(foreign, 0);
  EXPECT_THROW(box->edge_param_on_face(foreign, 1, 0.5), std::invalid_argument);
}

TEST(OccBuiltins, ExplicitHealingToleranceRunsShapeFixAndKeepsTheModel) {
  LoadOptions heal;
  heal.heal_tolerance = 1e-6;
  const auto healed = load_model("builtin:part", heal);
  const auto plain = load_model("builtin:part");
  EXPECT_EQ(healed->count(3), 1);
  EXPECT_EQ(healed->count(2), plain->count(2));
  EXPECT_NEAR(healed->volume(1), plain->volume(1), 1e-6 * plain->volume(1));
  LoadOptions raw;
  raw.heal = false;
  EXPECT_NEAR(load_model("builtin:part", raw)->volume(1), plain->volume(1), 1e-9 * plain->volume(1));
}

TEST(OccBuiltins, BadSpecificationsAreInputErrors) {
  expect_error<InputError>("builtin:teapot", "unknown built-in model 'teapot'");
  expect_error<InputError>("builtin:box:dx=1,width=2", "no parameter 'width'");
  expect_error<InputError>("builtin:box:dx=abc", "not a number");
  expect_error<InputError>("builtin:box:dx", "expected key=value");
  expect_error<InputError>("builtin:sphere:r=-1", "r must be > 0");
  expect_error<InputError>("builtin:torus:R=1,r=2", "R must be > r");
  expect_error<InputError>("builtin:cone:r1=1,r2=1", "different");
}

TEST(OccBuiltins, HelpListsEveryBuiltinWithDefaults) {
  const std::string help = builtin_help();
  for (const char* name : {"box", "sphere", "cylinder", "torus", "cone", "part", "blocks", "inclusion"})
    EXPECT_NE(help.find(std::string("builtin:") + name), std::string::npos) << name;
  EXPECT_NE(help.find("R=2,r=0.5"), std::string::npos);
}

}  // namespace
}  // namespace cm::geom_occ

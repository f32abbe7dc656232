// Every shared CAD model, at a coarse size (bounding-box diagonal / 8 with
// curvature sizing about Gmsh's MeshSizeFromCurvature 12) and a medium one
// (curvemesh's defaults), curved to orders 2 and 3: not one element left
// certified invalid or unacceptable, and the mesh still valid.
#include <filesystem>

#include <gtest/gtest.h>

#include "curved_support.hpp"
#include "curvemesh/mesh/validate.hpp"

namespace cm::test {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> shared_models() {
  std::vector<std::string> out;
  const fs::path dir = fs::path(CM_SHARED_DIR) / "models";
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".step" || ext == ".stp" || ext == ".brep") out.push_back(e.path().filename().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

struct Size {
  const char* name;
  double alpha;
  double diagonal_fraction;  // hmax = diagonal * this; 0: the default
};

class CurvedSharedModels : public ::testing::TestWithParam<std::tuple<std::string, Size>> {};

TEST_P(CurvedSharedModels, OrdersTwoAndThreeEndCertifiedValidAndAcceptable) {
  const auto& [file, size] = GetParam();
  const auto model = geom_occ::load_model(model_path(file));
  const double hmax = size.diagonal_fraction * model->bounding_box().diagonal();
  Meshed r = mesh_for_curving(file, size.alpha, hmax);
  for (int order : {2, 3}) {
    mesh::TetMesh m = r.m;
    curved::CurveOptions o;
    o.order = order;
    const curved::CurveReport rep = curved::curve_mesh(m, *r.model, o);
    EXPECT_EQ(rep.after.invalid.size(), 0u) << "order " << order;
    EXPECT_EQ(rep.after.unacceptable.size(), 0u) << "order " << order;
    const auto v = mesh::validate(m, mesh::Level::kFull);
    EXPECT_TRUE(v.valid()) << "order " << order << ": " << (v.issues.empty() ? "" : v.issues.front().message);
    RecordProperty("order" + std::to_string(order) + "_unacceptable_before", static_cast<int>(rep.unacceptable_before));
    RecordProperty("order" + std::to_string(order) + "_straightened", static_cast<int>(rep.repair.edges_straightened));
  }
}

INSTANTIATE_TEST_SUITE_P(Models, CurvedSharedModels,
                         ::testing::Combine(::testing::ValuesIn(shared_models()),
                                            ::testing::Values(Size{"coarse", 0.065, 1.0 / 8}, Size{"medium", 0.04, 0})),
                         [](const auto& param_info) {
                           std::string s = std::get<0>(param_info.param) + "_" + std::get<1>(param_info.param).name;
                           for (char& c : s)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return s;
                         });

}  // namespace
}  // namespace cm::test

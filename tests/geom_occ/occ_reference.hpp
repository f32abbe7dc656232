#pragma once
// Independent OpenCASCADE readings of the test models, to check OccModel
// against: the file read with OCC's defaults (STEP/IGES converted to mm),
// its solids (general-fused when there are several, as load_model does), and
// the TopExp maps whose indices are the expected tags.
#include <string>
#include <vector>

#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Shape.hxx>

#include "curvemesh/core/types.hpp"

namespace cm::test {

struct Reference {
  TopoDS_Shape raw;     // as read, before dropping free entities or fusing
  TopoDS_Shape solids;  // compound of the (fused) solids
  TopTools_IndexedMapOfShape vertices, edges, faces, solids_map;
};

/// The model files of CM_SHARED_DIR/models (STEP and B-rep), sorted.
std::vector<std::string> model_files();

/// Reads `path` with OCC defaults (STEP in mm) and builds the maps.
Reference read_reference(const std::string& path);

/// Millimetres per model unit ("" and "mm" are 1).
double mm_per_unit(const std::string& units);

/// Base name of a path, for test names and messages.
std::string base_name(const std::string& path);

inline Vec3 scaled(const Vec3& p, double f) { return p * f; }

}  // namespace cm::test
